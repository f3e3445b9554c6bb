// CalculiX deck writer, runner and .dat reader (see calculix.hpp): the tests' cross-check.
#include "support/calculix.hpp"

#include <fmt/format.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace phymul::fem {

namespace fs = std::filesystem;

namespace {

// Newton tolerances for NLGEOM steps (*CONTROLS, PARAMETERS=FIELD): largest residual over the
// average nodal force, largest correction over the increment's largest displacement, and
// the residual criterion used after the 9th iteration.
constexpr double kResidual = 1e-6, kCorrection = 1e-5, kResidualLate = 1e-5;

[[noreturn]] void reject(const std::string& what) {
  throw std::invalid_argument("calculix_deck: " + what);
}

// "1e-05" -> "1e-5": Fortran reads both, the short one leaves room for digits.
std::string compact_exponent(std::string text) {
  const std::size_t e = text.find('e');
  if (e == std::string::npos) return text;
  std::size_t digits = e + 1;
  if (digits < text.size() && (text[digits] == '-' || text[digits] == '+')) ++digits;
  std::size_t first = digits;
  while (first + 1 < text.size() && text[first] == '0') ++first;
  return text.erase(digits, first - digits);
}

// A real for a data line: CalculiX reads each field with the Fortran format (f20.0), so at
// most 20 characters; the shortest text that reads back to the same double when that fits
// (it does for all but a few 17-digit values), otherwise 15 or 16 significant digits.
std::string number(double value) {
  std::string text = compact_exponent(fmt::format("{}", value));
  for (int digits = 16; text.size() > 20 && digits > 0; --digits) {
    text = compact_exponent(fmt::format("{:.{}g}", value, digits));
  }
  return text;
}

std::string set_name(const std::string& name) {
  std::string out;
  for (char c : name) {
    const bool keep = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    out += keep ? char(std::toupper(static_cast<unsigned char>(c))) : '_';
  }
  return out;
}

// "*NSET, NSET=name" and the 1-based ids, 8 per line (CalculiX reads at most 16).
void write_node_set(std::string& deck, const std::string& name, const std::vector<int>& nodes) {
  deck += "*NSET, NSET=" + name + "\n";
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    deck += std::to_string(nodes[i] + 1);
    deck += (i + 1 == nodes.size() || i % 8 == 7) ? "\n" : ", ";
  }
}

void check_material(const Material& material) {
  if (!(std::isfinite(material.young) && material.young > 0.0)) {
    reject(fmt::format("Young's modulus must be finite and > 0 Pa (got {})", material.young));
  }
  if (!(material.poisson > -1.0 && material.poisson < 0.5)) {
    reject(fmt::format("Poisson's ratio must be in (-1, 0.5) (got {})", material.poisson));
  }
  if (material.law != Law::neo_hookean && material.law != Law::linear) {
    reject("unknown material law " + std::to_string(int(material.law)));
  }
}

std::string material_cards(const Material& material) {
  const double e = material.young, nu = material.poisson;
  if (material.law == Law::linear) {
    return fmt::format(
        "** Law::linear: small-strain linear elasticity, E = {} Pa, nu = {}\n"
        "*MATERIAL, NAME=TISSUE\n*ELASTIC\n{}, {}\n",
        number(e), number(nu), number(e), number(nu));
  }
  const double mu = e / (2.0 * (1.0 + nu)), kappa = e / (3.0 * (1.0 - 2.0 * nu));
  const double c10 = 0.5 * mu, d1 = 2.0 / kappa;
  return fmt::format(
      "** Law::neo_hookean: U = C10 (I1bar - 3) + 1/D1 (J - 1)^2, C10 = mu/2, D1 = 2/K\n"
      "** E = {} Pa, nu = {}: mu = {} Pa, K = {} Pa\n"
      "*MATERIAL, NAME=TISSUE\n*HYPERELASTIC, NEO HOOKE\n{}, {}\n",
      number(e), number(nu), number(mu), number(kappa), number(c10), number(d1));
}

struct ElementBlock {
  std::string type, elset;
  std::vector<std::array<int, 8>> nodes;  // 0-based, CalculiX order
  int count = 0;                          // nodes per element
};

std::vector<ElementBlock> element_blocks(const Mesh& mesh, const std::string& hexa_element) {
  ElementBlock hexa{hexa_element, "EHEXA", {}, 8}, tetra{"C3D4", "ETETRA", {}, 4},
      wedge{"C3D6", "EWEDGE", {}, 6};
  for (const Cell& cell : mesh.cells) {
    const auto& n = cell.nodes;
    switch (cell.type) {
      case CellType::hexa:  // CalculiX C3D8 order = VTK hexahedron order
        hexa.nodes.push_back(n);
        break;
      case CellType::tetra:  // CalculiX C3D4 order = VTK tetra order
        tetra.nodes.push_back({n[0], n[1], n[2], n[3], -1, -1, -1, -1});
        break;
      case CellType::wedge:  // VTK's 0-1-2 faces away from 3-4-5, CalculiX's towards it
        wedge.nodes.push_back({n[0], n[2], n[1], n[3], n[5], n[4], -1, -1});
        break;
      default:
        reject(std::string("surface cell type ") + cell_type_name(cell.type) + " in a volume mesh");
    }
  }
  std::vector<ElementBlock> blocks;
  for (ElementBlock* b : {&hexa, &tetra, &wedge}) {
    if (!b->nodes.empty()) blocks.push_back(std::move(*b));
  }
  return blocks;
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string ccx_program() {
  const char* env = std::getenv("PHYMUL_CCX");
  return env && *env ? std::string(env) : std::string("ccx");
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The last lines of a log, at most `lines` of them and about `chars` characters.
std::string tail(const std::string& text, int lines = 25, std::size_t chars = 3000) {
  std::size_t end = text.find_last_not_of(" \n\r\t");
  if (end == std::string::npos) return "(empty)";
  std::size_t begin = end + 1;
  for (int i = 0; i < lines && begin > 0; ++i) {
    const std::size_t nl = text.rfind('\n', begin - 1);
    begin = nl == std::string::npos ? 0 : nl;
    if (begin == 0) break;
  }
  if (end + 1 - begin > chars) begin = end + 1 - chars;
  return text.substr(begin, end + 1 - begin);
}

// A number as CalculiX prints it: "-3.000000E-03", or with a three-digit exponent
// "1.234567-100" (Fortran drops the 'E').
bool parse_real(const std::string& token, double& value) {
  const char* begin = token.c_str();
  char* end = nullptr;
  value = std::strtod(begin, &end);
  if (end == begin) return false;
  if (*end == '\0') return true;
  if ((*end == '-' || *end == '+') && end != begin) {
    char* exponent_end = nullptr;
    const long exponent = std::strtol(end, &exponent_end, 10);
    if (*exponent_end != '\0' || exponent_end == end + 1) return false;
    value *= std::pow(10.0, double(exponent));
    return true;
  }
  return false;
}

}  // namespace

std::string calculix_deck(const Mesh& mesh, const Material& material,
                          const std::vector<Dirichlet>& prescribed, int increments,
                          const std::string& element) {
  if (element != "C3D8I" && element != "C3D8" && element != "C3D8R") {
    reject("element must be C3D8I, C3D8 or C3D8R for the hexahedra (got \"" + element + "\")");
  }
  if (increments < 1) reject("increments must be >= 1 (got " + std::to_string(increments) + ")");
  check_material(material);
  if (mesh.cells.empty() || !mesh.volumetric()) reject("the mesh must have volumetric cells only");
  validate(mesh);  // positive cells: the node orders below are then CalculiX's positive ones

  const int n = int(mesh.points.size());
  std::map<std::pair<int, int>, double> bc;  // (node, axis) -> value
  for (const Dirichlet& d : prescribed) {
    if (d.node < 0 || d.node >= n) {
      reject(fmt::format("prescribed node {} is out of range (mesh has {} nodes)", d.node, n));
    }
    if (d.axis < 0 || d.axis > 2) {
      reject(fmt::format("prescribed axis {} of node {} must be 0, 1 or 2", d.axis, d.node));
    }
    if (!std::isfinite(d.value)) {
      reject(fmt::format("prescribed value of node {} axis {} is not finite", d.node, d.axis));
    }
    if (!bc.emplace(std::pair{d.node, d.axis}, d.value).second) {
      reject(fmt::format("node {} axis {} is prescribed twice", d.node, d.axis));
    }
  }

  const bool nonlinear = material.law == Law::neo_hookean;
  std::string deck;
  deck += "** phymul::fem::calculix_deck: static, displacements prescribed (ramped to time 1)\n";
  deck +=
      fmt::format("** {} nodes, {} cells, {} prescribed components; units of the mesh (m, N, Pa)\n",
                  n, mesh.cells.size(), prescribed.size());
  deck += "*NODE, NSET=NALL\n";
  for (int i = 0; i < n; ++i) {
    const Vec3& p = mesh.points[i];
    deck += fmt::format("{}, {}, {}, {}\n", i + 1, number(p.x()), number(p.y()), number(p.z()));
  }

  int element_id = 1;
  const std::vector<ElementBlock> blocks = element_blocks(mesh, element);
  for (const ElementBlock& block : blocks) {
    deck += "*ELEMENT, TYPE=" + block.type + ", ELSET=" + block.elset + "\n";
    for (const auto& nodes : block.nodes) {
      deck += std::to_string(element_id++);
      for (int k = 0; k < block.count; ++k) deck += ", " + std::to_string(nodes[k] + 1);
      deck += "\n";
    }
  }

  std::set<int> constrained;
  for (const auto& [key, value] : bc) constrained.insert(key.first);
  if (!constrained.empty()) write_node_set(deck, "NCONS", {constrained.begin(), constrained.end()});
  for (const auto& [name, nodes] : mesh.node_sets) {
    const std::string upper = set_name(name);
    if (nodes.empty() || upper.empty() || upper == "NALL" || upper == "NCONS") continue;
    write_node_set(deck, upper, nodes);
  }

  deck += material_cards(material);
  for (const ElementBlock& block : blocks) {
    deck += "*SOLID SECTION, ELSET=" + block.elset + ", MATERIAL=TISSUE\n";
  }

  const double dt = 1.0 / increments;
  if (nonlinear) {
    deck += fmt::format("*STEP, NLGEOM, INC={}\n*STATIC\n{}, 1.0, {}, {}\n",
                        std::max(100, 50 * increments), number(dt), number(1e-5 * dt), number(dt));
    // ccx's default Newton tolerances (largest residual 0.5 % of the average nodal force,
    // correction 1 % of the increment) are too loose for a 1 % cross-check.
    deck += fmt::format("*CONTROLS, PARAMETERS=FIELD\n{}, {}, , , {}\n", number(kResidual),
                        number(kCorrection), number(kResidualLate));
  } else {
    deck += "*STEP\n*STATIC\n1.0, 1.0\n";
  }
  deck += "*BOUNDARY\n";
  for (const auto& [key, value] : bc) {
    const int dof = key.second + 1;
    deck += fmt::format("{}, {}, {}, {}\n", key.first + 1, dof, dof, number(value));
  }
  deck += "*NODE PRINT, NSET=NALL\nU\n";
  if (!constrained.empty()) deck += "*NODE PRINT, NSET=NCONS\nRF\n";
  deck += "*END STEP\n";
  return deck;
}

CalculixResult parse_calculix_dat(const std::string& text) {
  enum class Table { none, displacement, force };
  struct Accumulator {
    double time = -1.0;
    std::map<int, Vec3> values;
  };
  Accumulator tables[3];
  Table current = Table::none;
  CalculixResult result;

  std::istringstream lines(text);
  std::string line;
  int line_number = 0;
  while (std::getline(lines, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const bool displacement = line.find("displacements (vx,vy,vz)") != std::string::npos;
    const bool force = line.find("forces (fx,fy,fz)") != std::string::npos &&
                       line.find("total force") == std::string::npos;
    if (displacement || force) {
      current = displacement ? Table::displacement : Table::force;
      double time = 0.0;
      const std::size_t at = line.rfind("time");
      std::istringstream value(at == std::string::npos ? "" : line.substr(at + 4));
      std::string token;
      if (!(value >> token) || !parse_real(token, time)) {
        result.message = fmt::format("job.dat line {}: no time in \"{}\"", line_number, line);
        return result;
      }
      Accumulator& table = tables[int(current)];
      if (table.time != time) table.values.clear();
      table.time = time;
      continue;
    }
    std::istringstream fields(line);
    std::string id_text, x, y, z, extra;
    fields >> id_text >> x >> y >> z;
    const bool row =
        !id_text.empty() && id_text.find_first_not_of("0123456789") == std::string::npos;
    if (!row || z.empty() || (fields >> extra)) {
      current = Table::none;  // another kind of table (stresses, totals, ...)
      continue;
    }
    if (current == Table::none) continue;
    Vec3 v;
    if (!parse_real(x, v.x()) || !parse_real(y, v.y()) || !parse_real(z, v.z()) || !v.allFinite()) {
      result.message = fmt::format("job.dat line {}: unreadable or non-finite values in \"{}\"",
                                   line_number, line);
      return result;
    }
    tables[int(current)].values[std::stoi(id_text)] = v;
  }

  const Accumulator& u = tables[int(Table::displacement)];
  const Accumulator& f = tables[int(Table::force)];
  if (u.values.empty()) {
    result.message = "job.dat has no displacement table (*NODE PRINT of U)";
    return result;
  }
  const int count =
      std::max(u.values.rbegin()->first, f.values.empty() ? 0 : f.values.rbegin()->first);
  if (u.values.begin()->first < 1 || int(u.values.size()) != count) {
    result.message = fmt::format(
        "job.dat: the displacement table at time {} has {} nodes, ids {}..{}; expected 1..{}",
        u.time, u.values.size(), u.values.begin()->first, u.values.rbegin()->first, count);
    return result;
  }
  result.displacement.assign(count, Vec3::Zero());
  result.reaction.assign(count, Vec3::Zero());
  for (const auto& [id, v] : u.values) result.displacement[id - 1] = v;
  if (!f.values.empty() && f.time != u.time) {
    result.message =
        fmt::format("job.dat: last forces at time {} but last displacements at {}", f.time, u.time);
    return result;
  }
  for (const auto& [id, v] : f.values) {
    if (id < 1) {
      result.message = fmt::format("job.dat: force table has node id {}", id);
      return result;
    }
    result.reaction[id - 1] = v;
  }
  result.time = u.time;
  result.ok = true;
  return result;
}

bool calculix_available() {
  static const bool available = [] {
    FILE* pipe = popen((shell_quote(ccx_program()) + " -v 2>&1 </dev/null").c_str(), "r");
    if (!pipe) return false;
    std::string output;
    std::array<char, 1024> buffer{};
    while (std::size_t got = std::fread(buffer.data(), 1, buffer.size(), pipe)) {
      output.append(buffer.data(), got);
    }
    pclose(pipe);  // ccx -v exits with status 201: judge by what it prints
    return output.find("Version") != std::string::npos;
  }();
  return available;
}

CalculixResult run_calculix(const std::string& deck, const fs::path& work_dir) {
  CalculixResult result;
  const std::string program = ccx_program();
  if (!calculix_available()) {
    result.message = "CalculiX is not available: '" + program +
                     " -v' did not run or print its version (install calculix-ccx, or set "
                     "PHYMUL_CCX to the ccx executable)";
    return result;
  }
  std::error_code error;
  fs::create_directories(work_dir, error);
  if (error) {
    result.message = "cannot create " + work_dir.string() + ": " + error.message();
    return result;
  }
  const fs::path dat = work_dir / "job.dat", log = work_dir / "ccx.log";
  fs::remove(dat, error);  // never read an earlier run's results
  {
    std::ofstream inp(work_dir / "job.inp", std::ios::binary);
    inp << deck;
    if (!inp.flush()) {
      result.message = "cannot write " + (work_dir / "job.inp").string();
      return result;
    }
  }

  const std::string command = "cd " + shell_quote(work_dir.string()) + " && OMP_NUM_THREADS=1 " +
                              shell_quote(program) + " -i job > ccx.log 2>&1 < /dev/null";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string log_text = read_file(log);
  const auto fail = [&](const std::string& why) {
    result.ok = false;
    result.message = why + " (in " + work_dir.string() + ")";
    const std::size_t error_at = log_text.find("*ERROR");
    if (error_at != std::string::npos) {  // the first error with the card it names
      std::size_t end = error_at;
      for (int i = 0; i < 6 && end != std::string::npos; ++i) end = log_text.find('\n', end + 1);
      result.message += "; first error in ccx.log:\n" +
                        log_text.substr(error_at, std::min(end, error_at + 1500) - error_at);
    }
    result.message += "\nend of ccx.log:\n" + tail(log_text);
    return result;
  };

  if (status == -1) return fail("could not start a shell for ccx");
  if (!WIFEXITED(status))
    return fail("ccx was killed (wait status " + std::to_string(status) + ")");
  if (WEXITSTATUS(status) != 0) {
    return fail("ccx exited with status " + std::to_string(WEXITSTATUS(status)));
  }
  if (log_text.find("*ERROR") != std::string::npos) return fail("ccx reported *ERROR");
  if (!fs::exists(dat)) return fail("ccx wrote no job.dat");

  CalculixResult parsed = parse_calculix_dat(read_file(dat));
  parsed.wall_seconds = result.wall_seconds;
  if (!parsed.ok) return fail(parsed.message);
  return parsed;
}

}  // namespace phymul::fem

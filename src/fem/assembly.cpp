// Assembly into a fixed sparsity pattern: every element entry knows where its value goes, so
// each Newton iteration only zeroes the value arrays and adds into them (no triplets, no
// sorting), and the sparse factorisation can keep its symbolic analysis.
#include <Eigen/SparseCore>
#include <algorithm>
#include <stdexcept>

#include "fem/system.hpp"

namespace phymul::fem {

namespace {

template <int NN>
Eigen::Matrix<double, 3, NN> gather_nodes(const std::vector<Vec3>& points,
                                          const std::array<int, 8>& nodes) {
  Eigen::Matrix<double, 3, NN> x;
  for (int a = 0; a < NN; ++a) x.col(a) = points[nodes[a]];
  return x;
}

// Position of (row, col) in the values of a compressed column-major matrix holding it.
int value_position(const SparseMatrix& m, int row, int col) {
  const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[col];
  const int* end = m.innerIndexPtr() + m.outerIndexPtr()[col + 1];
  return int(std::lower_bound(begin, end, row) - m.innerIndexPtr());
}

}  // namespace

System::System(const Mesh& mesh, const Material& material, std::vector<char> prescribed)
    : System(mesh, std::vector<Material>{material}, std::vector<int>(mesh.cells.size(), 0),
             std::move(prescribed)) {}

System::System(const Mesh& mesh, const std::vector<Material>& materials,
               const std::vector<int>& cell_material, std::vector<char> prescribed) {
  for (const Material& m : materials) laws_.push_back({m.law, moduli(m)});
  const int nodes = int(mesh.points.size());
  std::vector<char> used(nodes, 0);
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const Cell& cell = mesh.cells[c];
    Element e;
    e.type = cell.type;
    e.nodes = cell.nodes;
    e.law = cell_material[c];
    for (int n : cell.node_span()) used[n] = 1;
    if (cell.type == CellType::hexa &&
        materials[size_t(e.law)].hexa == HexaElement::incompatible_modes) {
      e.incompatible = true;
      e.reference = int(incompatible_.size());
      incompatible_.push_back(
          incompatible_hexa_reference(gather_nodes<8>(mesh.points, cell.nodes), int(c)));
      modes_.push_back(ModeAmplitudes::Zero());
    } else if (cell.type == CellType::hexa) {
      e.reference = int(hexa_.size());
      hexa_.push_back(hexa_reference(gather_nodes<8>(mesh.points, cell.nodes), int(c)));
    } else {
      e.reference = int(tetra_.size());
      tetra_.push_back(tetra_reference(gather_nodes<4>(mesh.points, cell.nodes), int(c)));
    }
    elements_.push_back(e);
  }
  dof_index_.resize(3 * std::size_t(nodes));
  for (int d = 0; d < 3 * nodes; ++d) {
    if (prescribed[d] || !used[d / 3]) {
      dof_index_[d] = -1 - int(prescribed_dofs_.size());
      prescribed_dofs_.push_back(d);
    } else {
      dof_index_[d] = int(free_dofs_.size());
      free_dofs_.push_back(d);
    }
  }
  internal_ = Eigen::VectorXd::Zero(3 * nodes);
  build_pattern();
}

void System::build_pattern() {
  std::vector<Eigen::Triplet<double, int>> ff, fp;
  const auto for_each_entry = [&](auto&& visit) {
    for (const Element& e : elements_) {
      const int n = 3 * node_count(e.type);
      for (int c = 0; c < n; ++c) {
        for (int r = 0; r < n; ++r) {
          visit(e, r, c, dof_index_[3 * e.nodes[r / 3] + r % 3],
                dof_index_[3 * e.nodes[c / 3] + c % 3]);
        }
      }
    }
  };
  for_each_entry([&](const Element&, int, int, int row, int col) {
    if (row >= 0 && col >= 0 && row >= col) ff.emplace_back(row, col, 0.0);
    if (row >= 0 && col < 0) fp.emplace_back(row, -1 - col, 0.0);
  });
  k_ff_.resize(free_count(), free_count());
  k_ff_.setFromTriplets(ff.begin(), ff.end());
  k_ff_.makeCompressed();
  k_fp_.resize(free_count(), prescribed_count());
  k_fp_.setFromTriplets(fp.begin(), fp.end());
  k_fp_.makeCompressed();

  int offset = 0;
  for (Element& e : elements_) {
    e.slots = offset;
    offset += 9 * node_count(e.type) * node_count(e.type);
  }
  slot_.assign(offset, -1);
  for_each_entry([&](const Element& e, int r, int c, int row, int col) {
    const int n = 3 * node_count(e.type);
    int& slot = slot_[e.slots + r + n * c];
    if (row >= 0 && col >= 0 && row >= col) slot = value_position(k_ff_, row, col);
    if (row >= 0 && col < 0) slot = -2 - value_position(k_fp_, row, -1 - col);
  });
}

Eigen::VectorXd System::body_force(const Vec3& force_density) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(dof_count());
  for (const Element& e : elements_) {
    const int nn = node_count(e.type);
    for (int a = 0; a < nn; ++a) {
      const double share = e.incompatible             ? incompatible_[e.reference].nodal_volume(a)
                           : e.type == CellType::hexa ? hexa_[e.reference].nodal_volume(a)
                                                      : tetra_[e.reference].nodal_volume(a);
      f.segment<3>(3 * e.nodes[a]) += share * force_density;
    }
  }
  return f;
}

template <int NN, int NG>
bool System::add_element(const ElementReference<NN, NG>& ref, const Element& element,
                         const Eigen::VectorXd& u, bool with_tangent) {
  Eigen::Matrix<double, 3, NN> ue;
  for (int a = 0; a < NN; ++a) ue.col(a) = u.segment<3>(3 * element.nodes[a]);
  ElementResult<NN> out;
  if (!evaluate_element<NN, NG>(ref, ue, laws_[element.law], with_tangent, out)) return false;
  add_result<NN>(element, out, with_tangent);
  return true;
}

bool System::add_incompatible(const Element& element, const Eigen::VectorXd& u, bool with_tangent) {
  Eigen::Matrix<double, 3, 8> ue;
  for (int a = 0; a < 8; ++a) ue.col(a) = u.segment<3>(3 * element.nodes[a]);
  ElementResult<8> out;
  if (!evaluate_incompatible_hexa(incompatible_[element.reference], ue, laws_[element.law],
                                  with_tangent, modes_[element.reference], out))
    return false;
  add_result<8>(element, out, with_tangent);
  return true;
}

template <int NN>
void System::add_result(const Element& element, const ElementResult<NN>& out, bool with_tangent) {
  energy_ += out.energy;
  for (int a = 0; a < NN; ++a) internal_.segment<3>(3 * element.nodes[a]) += out.force.col(a);
  if (!with_tangent) return;
  const int* slot = slot_.data() + element.slots;
  const double* value = out.stiffness.data();  // column-major, same order as the slots
  double* ff = k_ff_.valuePtr();
  double* fp = k_fp_.valuePtr();
  for (int i = 0; i < 9 * NN * NN; ++i) {
    if (slot[i] >= 0) {
      ff[slot[i]] += value[i];
    } else if (slot[i] <= -2) {
      fp[-2 - slot[i]] += value[i];
    }
  }
}

bool System::evaluate(const Eigen::VectorXd& u, bool with_tangent) {
  energy_ = 0.0;
  internal_.setZero();
  if (with_tangent) {
    std::fill_n(k_ff_.valuePtr(), k_ff_.nonZeros(), 0.0);
    std::fill_n(k_fp_.valuePtr(), k_fp_.nonZeros(), 0.0);
  }
  for (const Element& e : elements_) {
    const bool ok = e.incompatible ? add_incompatible(e, u, with_tangent)
                    : e.type == CellType::hexa
                        ? add_element<8, 8>(hexa_[e.reference], e, u, with_tangent)
                        : add_element<4, 1>(tetra_[e.reference], e, u, with_tangent);
    if (!ok) return false;
  }
  return true;
}

Eigen::VectorXd System::gather(const Eigen::VectorXd& full, const std::vector<int>& dofs) const {
  Eigen::VectorXd part(dofs.size());
  for (std::size_t i = 0; i < dofs.size(); ++i) part[Eigen::Index(i)] = full[dofs[i]];
  return part;
}

void System::scatter_add(const Eigen::VectorXd& part, const std::vector<int>& dofs,
                         Eigen::VectorXd& full) const {
  for (std::size_t i = 0; i < dofs.size(); ++i) full[dofs[i]] += part[Eigen::Index(i)];
}

namespace {

std::vector<double> values_of(const SparseMatrix& m) {
  return {m.valuePtr(), m.valuePtr() + m.nonZeros()};
}

void set_values(SparseMatrix& m, const std::vector<double>& values) {
  if (values.size() != size_t(m.nonZeros()))
    throw std::invalid_argument("fem: a saved tangent does not fit this system's pattern");
  std::copy(values.begin(), values.end(), m.valuePtr());
}

}  // namespace

void System::save_evaluation(SolveState& state) const {
  state.energy = energy_;
  state.internal_force.assign(internal_.data(), internal_.data() + internal_.size());
  state.tangent_ff = values_of(k_ff_);
  state.tangent_fp = values_of(k_fp_);
  state.mode_amplitudes.clear();
  for (const ModeAmplitudes& a : modes_)
    state.mode_amplitudes.insert(state.mode_amplitudes.end(), a.data(), a.data() + a.size());
}

void System::restore_evaluation(const SolveState& state) {
  if (state.internal_force.size() != size_t(internal_.size()) ||
      state.mode_amplitudes.size() != 9 * modes_.size())
    throw std::invalid_argument("fem: a saved evaluation does not fit this system");
  energy_ = state.energy;
  internal_ = Eigen::Map<const Eigen::VectorXd>(state.internal_force.data(), internal_.size());
  set_values(k_ff_, state.tangent_ff);
  set_values(k_fp_, state.tangent_fp);
  for (size_t e = 0; e < modes_.size(); ++e)
    modes_[e] = Eigen::Map<const ModeAmplitudes>(state.mode_amplitudes.data() + 9 * e);
}

std::vector<double> System::tangent_values() const { return values_of(k_ff_); }

void System::set_tangent_values(const std::vector<double>& values) { set_values(k_ff_, values); }

}  // namespace phymul::fem

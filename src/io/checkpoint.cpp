#include "phymul/checkpoint.hpp"

#include <fmt/format.h>

#include <array>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <tuple>

#include "io/checkpoint_fields.hpp"

namespace phymul {

namespace {

// Layout: magic, version, byte-order mark, payload size, payload, FNV-1a of the payload.
// Integers are 64-bit and doubles their IEEE bits, in this machine's byte order (the mark
// refuses a file from a machine of the other order).
constexpr char kMagic[8] = {'P', 'H', 'Y', 'M', 'U', 'L', 'C', 'K'};
constexpr std::uint64_t kVersion = 7;
constexpr std::uint64_t kByteOrderMark = 0x0102030405060708ULL;
constexpr std::size_t kHeaderBytes = sizeof kMagic + 3 * sizeof(std::uint64_t);

// Binary form of each member type; aggregates go member by member (fields::for_each), so the
// file holds every member of Checkpoint and of the Data inside it.
// Fixed-size Eigen vectors and matrices (Vec3): their coefficients, in storage order.
template <class T>
inline constexpr bool is_eigen_fixed = false;
template <class S, int R, int C, int O, int MR, int MC>
inline constexpr bool is_eigen_fixed<Eigen::Matrix<S, R, C, O, MR, MC>> = R > 0 && C > 0;

class Writer {
 public:
  template <class T>
  void put(const T& v) {
    if constexpr (fields::is_workspace<T>) {
      return;  // scratch no later step reads (model/workspace.hpp)
    } else if constexpr (std::is_same_v<T, bool>) {
      put(std::uint64_t(v ? 1 : 0));
    } else if constexpr (std::is_enum_v<T>) {
      put(static_cast<long long>(v));
    } else if constexpr (std::is_integral_v<T>) {
      raw_value(static_cast<std::conditional_t<std::is_signed_v<T>, long long, std::uint64_t>>(v));
    } else if constexpr (std::is_same_v<T, double>) {
      raw_value(v);
    } else if constexpr (std::is_same_v<T, std::string>) {
      put(std::uint64_t(v.size()));
      out_.append(v);
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      for (double c : {v.w(), v.x(), v.y(), v.z()}) put(c);
    } else if constexpr (is_eigen_fixed<T>) {
      for (Eigen::Index k = 0; k < v.size(); ++k) put(double(v.data()[k]));
    } else if constexpr (fields::is_vector<T>) {
      put(std::uint64_t(v.size()));
      for (const auto& e : v) put(e);
    } else if constexpr (fields::is_array<T>) {
      for (const auto& e : v) put(e);
    } else {
      fields::for_each(v, [&](std::string_view, const auto& member) { put(member); });
    }
  }
  void raw(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  const std::string& bytes() const { return out_; }

 private:
  template <class T>
  void raw_value(T v) {
    raw(&v, sizeof v);
  }
  std::string out_;
};

class Reader {
 public:
  Reader(std::string_view bytes, std::size_t base, const std::string& name)
      : in_(bytes), base_(base), name_(name) {}

  // Reads v's binary form; `field` names it in messages (a member's path).
  template <class T>
  void get(T& v, const std::string& field) {
    if constexpr (fields::is_workspace<T>) {
      return;  // the reader's Data keeps the workspace it was made with
    } else if constexpr (std::is_same_v<T, bool>) {
      const std::uint64_t b = scalar<std::uint64_t>(field);
      if (b > 1) fail(fmt::format("'{}' is {}, expected 0 or 1", field, b));
      v = b == 1;
    } else if constexpr (std::is_enum_v<T>) {
      v = static_cast<T>(scalar<long long>(field));
    } else if constexpr (std::is_integral_v<T>) {
      using Wide = std::conditional_t<std::is_signed_v<T>, long long, std::uint64_t>;
      const Wide w = scalar<Wide>(field);
      if (w < Wide(std::numeric_limits<T>::lowest()) || w > Wide(std::numeric_limits<T>::max()))
        fail(fmt::format("'{}' is {}, out of range", field, w));
      v = T(w);
    } else if constexpr (std::is_same_v<T, double>) {
      v = scalar<double>(field);
    } else if constexpr (std::is_same_v<T, std::string>) {
      const std::size_t n = count(field);
      v.assign(in_.substr(at_, n));
      at_ += n;
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      double c[4];
      for (double& e : c) e = scalar<double>(field);
      v = Eigen::Quaterniond(c[0], c[1], c[2], c[3]);
    } else if constexpr (is_eigen_fixed<T>) {
      for (Eigen::Index k = 0; k < v.size(); ++k) v.data()[k] = scalar<double>(field);
    } else if constexpr (fields::is_vector<T>) {
      v.resize(count(field));
      for (size_t k = 0; k < v.size(); ++k) get(v[k], field);
    } else if constexpr (fields::is_array<T>) {
      for (auto& e : v) get(e, field);
    } else {
      fields::for_each(v, [&](std::string_view name, auto& member) {
        get(member, field.empty() ? std::string(name) : field + "." + std::string(name));
      });
    }
  }
  void expect_end() const {
    if (at_ != in_.size())
      fail(fmt::format("{} bytes of unknown data after the last field", in_.size() - at_));
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw CheckpointError(
        fmt::format("checkpoint {} is corrupt at byte {}: {}", name_, base_ + at_, what));
  }

 private:
  template <class T>
  T scalar(const std::string& field) {
    T v;
    if (in_.size() - at_ < sizeof v)
      fail(fmt::format("'{}' needs {} bytes, {} are left", field, sizeof v, in_.size() - at_));
    std::memcpy(&v, in_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  // A count of items (a byte each at least) that must fit in what is left of the file.
  std::size_t count(const std::string& field) {
    const std::uint64_t n = scalar<std::uint64_t>(field);
    if (n > in_.size() - at_)
      fail(fmt::format("'{}' claims {} items, more than the {} bytes left", field, n,
                       in_.size() - at_));
    return std::size_t(n);
  }

  std::string_view in_;
  std::size_t at_ = 0, base_;
  const std::string& name_;
};

// What the file's fields must agree on among themselves (the model's sizes are checked by
// data_shape_mismatch when the run has its model).
void check_fields(Reader& r, const Checkpoint& c) {
  const Data& d = c.data;
  const size_t n = d.x.size();
  auto per_node = [&](size_t size, const char* field, bool may_be_empty) {
    if (size != n && !(may_be_empty && size == 0))
      r.fail(fmt::format("'data.{}' has {} entries where the checkpoint has {} nodes", field, size,
                         n));
  };
  per_node(d.v.size(), "v", false);
  per_node(d.f.size(), "f", false);
  per_node(d.acceleration.size(), "acceleration", true);
  per_node(d.obstacle_touching.size(), "obstacle_touching", true);
  auto non_negative = [&](long long v, const char* field) {
    if (v < 0) r.fail(fmt::format("'{}' is {}, expected 0 or more", field, v));
  };
  non_negative(d.step, "data.step");
  non_negative(c.steps_done, "steps_done");
  const StaticProgress& p = d.static_progress;
  non_negative(p.load_step, "data.static_progress.load_step");
  non_negative(p.iterations, "data.static_progress.iterations");
  non_negative(p.step_iterations, "data.static_progress.step_iterations");
  non_negative(p.fire_downhill, "data.static_progress.fire_downhill");
  for (const PvdEntry& e : c.frames)
    if (e.file.empty() || e.file.find('/') != std::string::npos ||
        e.file.find('\\') != std::string::npos)
      r.fail(fmt::format("frame file name '{}' is not a plain file name", e.file));
}

}  // namespace

std::filesystem::path checkpoint_path(const std::filesystem::path& output_dir) {
  return output_dir / "checkpoint.bin";
}

std::uint64_t fnv1a(std::string_view bytes, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::uint64_t file_hash(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CheckpointError(fmt::format("cannot read {}", file.string()));
  std::ostringstream s;
  s << in.rdbuf();
  return fnv1a(s.str());
}

std::uint64_t model_hash(const Model& model) {
  std::uint64_t h = fnv1a({});
  auto add = [&](const void* p, std::size_t n) { h = fnv1a({static_cast<const char*>(p), n}, h); };
  for (const Vec3& p : model.rest_position) add(p.data(), 3 * sizeof(double));
  add(model.mass.data(), model.mass.size() * sizeof(double));
  for (const Vec3& m : model.inverse_mass) add(m.data(), 3 * sizeof(double));
  for (const Cell& c : model.cells) {
    add(&c.type, sizeof c.type);
    add(c.nodes.data(), c.nodes.size() * sizeof(int));
  }
  return h;
}

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& checkpoint) {
  Writer w;
  w.put(checkpoint);
  const std::string& body = w.bytes();
  Writer header;
  header.raw(kMagic, sizeof kMagic);
  header.put(kVersion);
  header.put(kByteOrderMark);
  header.put(std::uint64_t(body.size()));
  const std::uint64_t sum = fnv1a(body);
  write_file_atomically(path, [&](std::ostream& o) {
    o.write(header.bytes().data(), std::streamsize(header.bytes().size()));
    o.write(body.data(), std::streamsize(body.size()));
    o.write(reinterpret_cast<const char*>(&sum), sizeof sum);
  });
}

Checkpoint parse_checkpoint(std::string_view bytes, const std::string& name) {
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw CheckpointError(
        fmt::format("{} is not a phymul checkpoint (it does not start with 'PHYMULCK')", name));
  if (bytes.size() < kHeaderBytes)
    throw CheckpointError(
        fmt::format("checkpoint {} is truncated: {} bytes, the header alone has {}", name,
                    bytes.size(), kHeaderBytes));
  std::uint64_t fields[3];
  std::memcpy(fields, bytes.data() + sizeof kMagic, sizeof fields);
  const auto [version, mark, size] = std::tuple(fields[0], fields[1], fields[2]);
  if (version != kVersion)
    throw CheckpointError(
        fmt::format("checkpoint {} has format version {}; this phymul reads version {}", name,
                    version, kVersion));
  if (mark != kByteOrderMark)
    throw CheckpointError(fmt::format(
        "checkpoint {} was written on a machine of another byte order (or is corrupt)", name));
  const std::size_t available = bytes.size() - kHeaderBytes;
  if (available < sizeof(std::uint64_t) || size != available - sizeof(std::uint64_t))
    throw CheckpointError(fmt::format(
        "checkpoint {} is truncated or corrupt: its header announces {} bytes of data and a "
        "checksum, the file holds {} bytes after the header",
        name, size, available));
  const std::string_view body = bytes.substr(kHeaderBytes, std::size_t(size));
  std::uint64_t sum;
  std::memcpy(&sum, bytes.data() + kHeaderBytes + size, sizeof sum);
  if (sum != fnv1a(body))
    throw CheckpointError(
        fmt::format("checkpoint {} is corrupt: its checksum does not match its contents", name));
  Reader r(body, kHeaderBytes, name);
  Checkpoint c;
  r.get(c, "");
  r.expect_end();
  check_fields(r, c);
  return c;
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw CheckpointError(fmt::format(
        "no checkpoint at {}: a run writes one with --checkpoint-every or when interrupted "
        "(a run that ended leaves none)",
        path.string()));
  std::ostringstream s;
  s << in.rdbuf();
  return parse_checkpoint(s.str(), path.string());
}

}  // namespace phymul

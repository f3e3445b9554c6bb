#include "io/checkpoint.hpp"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <tuple>

namespace phymul {
namespace {

// Layout: magic, version, byte-order mark, payload size, payload, FNV-1a of the payload.
// Integers are 64-bit and doubles their IEEE bits, in this machine's byte order (the mark
// refuses a file from a machine of the other order).
constexpr char kMagic[8] = {'P', 'H', 'Y', 'M', 'U', 'L', 'C', 'K'};
constexpr std::uint64_t kVersion = 1;
constexpr std::uint64_t kByteOrderMark = 0x0102030405060708ULL;
constexpr std::size_t kHeaderBytes = sizeof kMagic + 3 * sizeof(std::uint64_t);

class Writer {
 public:
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void i64(long long v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void text(std::string_view s) {
    u64(s.size());
    out_.append(s);
  }
  void vectors(const std::vector<Vec3>& v) {
    u64(v.size());
    for (const Vec3& p : v)
      for (int a = 0; a < 3; ++a) f64(p[a]);
  }
  void raw(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  const std::string& bytes() const { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  static constexpr std::size_t kAny = std::size_t(-1);
  Reader(std::string_view bytes, std::size_t base, const std::string& name)
      : in_(bytes), base_(base), name_(name) {}

  std::uint64_t u64(const char* field) {
    std::uint64_t v;
    take(&v, sizeof v, field);
    return v;
  }
  long long i64(const char* field) {
    long long v;
    take(&v, sizeof v, field);
    return v;
  }
  double f64(const char* field) {
    double v;
    take(&v, sizeof v, field);
    return v;
  }
  // A count of items of `item_bytes` each that must fit in what is left of the file.
  std::size_t count(const char* field, std::size_t item_bytes) {
    const std::uint64_t n = u64(field);
    if (n > (in_.size() - at_) / item_bytes)
      fail(fmt::format("'{}' claims {} items of {} bytes, more than the {} bytes left", field, n,
                       item_bytes, in_.size() - at_));
    return std::size_t(n);
  }
  std::string text(const char* field) {
    const std::size_t n = count(field, 1);
    std::string s(in_.substr(at_, n));
    at_ += n;
    return s;
  }
  std::vector<Vec3> vectors(const char* field, std::size_t expected = kAny) {
    const std::size_t n = count(field, 3 * sizeof(double));
    if (expected != kAny && n != expected)
      fail(
          fmt::format("'{}' has {} entries where the checkpoint has {} nodes", field, n, expected));
    std::vector<Vec3> v(n);
    for (Vec3& p : v)
      for (int a = 0; a < 3; ++a) p[a] = f64(field);
    return v;
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
  void take(void* p, std::size_t n, const char* field) {
    if (in_.size() - at_ < n)
      fail(fmt::format("'{}' needs {} bytes, {} are left", field, n, in_.size() - at_));
    std::memcpy(p, in_.data() + at_, n);
    at_ += n;
  }

  std::string_view in_;
  std::size_t at_ = 0, base_;
  const std::string& name_;
};

std::string payload(const Checkpoint& c) {
  Writer w;
  w.text(c.scene_file);
  w.u64(c.scene_hash);
  w.u64(c.model_hash);
  w.u64(c.static_mode ? 1 : 0);
  w.f64(c.dt);
  const State& s = c.state;
  w.f64(s.time);
  w.i64(s.step);
  w.vectors(s.x);
  w.vectors(s.v);
  w.vectors(s.f);
  w.u64(s.rotation.size());
  for (const Eigen::Quaterniond& q : s.rotation)
    for (double v : {q.w(), q.x(), q.y(), q.z()}) w.f64(v);
  w.f64(s.shape_memory_energy);
  w.u64(s.bodies.size());
  for (const RigidBodyState& b : s.bodies) {
    for (double v : {b.center.x(), b.center.y(), b.center.z()}) w.f64(v);
    for (double v : {b.orientation.w(), b.orientation.x(), b.orientation.y(), b.orientation.z()})
      w.f64(v);
    for (double v : {b.momentum.x(), b.momentum.y(), b.momentum.z()}) w.f64(v);
    for (double v : {b.angular_momentum.x(), b.angular_momentum.y(), b.angular_momentum.z()})
      w.f64(v);
  }
  w.f64(c.load_time);
  w.i64(c.static_progress.load_step);
  w.i64(c.static_progress.iterations);
  w.i64(c.static_progress.step_iterations);
  w.f64(c.static_progress.previous_kinetic);
  w.f64(c.static_progress.fire_alpha);
  w.i64(c.static_progress.fire_downhill);
  w.i64(c.steps_done);
  w.f64(c.next_frame);
  w.u64(c.frames.size());
  for (const PvdEntry& e : c.frames) {
    w.f64(e.time);
    w.text(e.file);
  }
  w.text(c.monitors);
  return w.bytes();
}

long non_negative(Reader& r, long long v, const char* field) {
  if (v < 0) r.fail(fmt::format("'{}' is {}, expected 0 or more", field, v));
  return long(v);
}

Checkpoint parse_payload(Reader& r) {
  Checkpoint c;
  c.scene_file = r.text("scene file");
  c.scene_hash = r.u64("scene hash");
  c.model_hash = r.u64("model hash");
  const std::uint64_t mode = r.u64("mode");
  if (mode > 1) r.fail(fmt::format("'mode' is {}, expected 0 (dynamic) or 1 (static)", mode));
  c.static_mode = mode == 1;
  c.dt = r.f64("dt");
  State& s = c.state;
  s.time = r.f64("time");
  s.step = non_negative(r, r.i64("step"), "step");
  s.x = r.vectors("positions");
  s.v = r.vectors("velocities", s.x.size());
  s.f = r.vectors("forces", s.x.size());
  s.rotation.resize(r.count("rotations", 4 * sizeof(double)));
  for (Eigen::Quaterniond& q : s.rotation) {
    const double w = r.f64("rotations"), x = r.f64("rotations"), y = r.f64("rotations"),
                 z = r.f64("rotations");
    q = Eigen::Quaterniond(w, x, y, z);
  }
  s.shape_memory_energy = r.f64("shape memory energy");
  s.bodies.resize(r.count("rigid bodies", 13 * sizeof(double)));
  for (RigidBodyState& b : s.bodies) {
    auto vec = [&r](const char* field) {
      const double x = r.f64(field), y = r.f64(field), z = r.f64(field);
      return Vec3(x, y, z);
    };
    b.center = vec("rigid body centre");
    const double w = r.f64("rigid body orientation"), x = r.f64("rigid body orientation"),
                 y = r.f64("rigid body orientation"), z = r.f64("rigid body orientation");
    b.orientation = Eigen::Quaterniond(w, x, y, z);
    b.momentum = vec("rigid body momentum");
    b.angular_momentum = vec("rigid body angular momentum");
  }
  c.load_time = r.f64("load time");
  StaticProgress& p = c.static_progress;
  p.load_step = int(non_negative(r, r.i64("load step"), "load step"));
  p.iterations = non_negative(r, r.i64("iterations"), "iterations");
  p.step_iterations = non_negative(r, r.i64("load step iterations"), "load step iterations");
  p.previous_kinetic = r.f64("previous kinetic energy");
  p.fire_alpha = r.f64("FIRE mixing");
  p.fire_downhill = non_negative(r, r.i64("FIRE downhill steps"), "FIRE downhill steps");
  c.steps_done = non_negative(r, r.i64("steps done"), "steps done");
  c.next_frame = r.f64("next frame time");
  c.frames.resize(r.count("frames", sizeof(double) + sizeof(std::uint64_t)));
  for (PvdEntry& e : c.frames) {
    e.time = r.f64("frame time");
    e.file = r.text("frame file");
    if (e.file.empty() || e.file.find('/') != std::string::npos ||
        e.file.find('\\') != std::string::npos)
      r.fail(fmt::format("frame file name '{}' is not a plain file name", e.file));
  }
  c.monitors = r.text("monitors");
  r.expect_end();
  return c;
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
  const std::string body = payload(checkpoint);
  Writer header;
  header.raw(kMagic, sizeof kMagic);
  header.u64(kVersion);
  header.u64(kByteOrderMark);
  header.u64(body.size());
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
  return parse_payload(r);
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

// NIfTI-1 label images: the 348-byte header (either byte order), the frame, the voxels.
#include "phymul/nifti.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "io/gzip.hpp"

namespace phymul {
namespace {

constexpr size_t kHeaderSize = 348;

// std::byteswap is C++23.
template <class U>
U swapped(U bits) {
  if constexpr (sizeof(U) == 1) return bits;
  if constexpr (sizeof(U) == 2) return U(__builtin_bswap16(bits));
  if constexpr (sizeof(U) == 4) return U(__builtin_bswap32(bits));
  if constexpr (sizeof(U) == 8) return U(__builtin_bswap64(bits));
}

// The header's bytes, read as the file's byte order says.
struct Header {
  std::string_view bytes;
  bool swap = false;

  template <class T>
  T get(size_t offset) const {
    using U = std::conditional_t<
        sizeof(T) == 1, std::uint8_t,
        std::conditional_t<sizeof(T) == 2, std::uint16_t,
                           std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
    U bits;
    std::memcpy(&bits, bytes.data() + offset, sizeof(T));
    if (swap) bits = swapped(bits);
    return std::bit_cast<T>(bits);
  }
  std::int16_t i16(size_t offset) const { return get<std::int16_t>(offset); }
  float f32(size_t offset) const { return get<float>(offset); }
};

struct Reader {
  std::string name;
  std::vector<std::string>* notes;
  bool gzip = false;

  [[noreturn]] void fail(const std::string& message) const {
    throw MeshFileError(name, 0, 0, message);
  }
  void note(const std::string& text) const {
    if (notes) notes->push_back(fmt::format("{}: {}", name, text));
  }
  // A header number that must be finite, named as the NIfTI standard names it.
  double finite(const Header& h, size_t offset, const std::string& field) const {
    const double v = h.f32(offset);
    if (!std::isfinite(v))
      fail(fmt::format("header field {} is {}, expected a finite number", field, v));
    return v;
  }
};

Header byte_order(std::string_view bytes, const Reader& r) {
  if (bytes.size() < kHeaderSize)
    r.fail(
        fmt::format("{} bytes{}, too short for a NIfTI-1 header ({} bytes): truncated, or "
                    "not a NIfTI file",
                    bytes.size(), r.gzip ? " once decompressed" : "", kHeaderSize));
  Header h{bytes, false};
  const std::int32_t size = h.get<std::int32_t>(0);
  if (size == 348) return h;
  if (std::int32_t(swapped(std::uint32_t(size))) == 348) return {bytes, true};
  if (size == 540 || std::int32_t(swapped(std::uint32_t(size))) == 540)
    r.fail(
        "a NIfTI-2 file (sizeof_hdr 540): only NIfTI-1 is read (save it as NIfTI-1, e.g. "
        "nibabel's Nifti1Image)");
  r.fail(fmt::format("header field sizeof_hdr is {}, expected 348 (a NIfTI-1 file)", size));
}

void check_magic(const Header& h, const Reader& r) {
  const std::string_view magic = h.bytes.substr(344, 4);
  if (magic == std::string_view("ni1\0", 4))
    r.fail(
        "magic 'ni1': a .hdr/.img pair; only single-file NIfTI-1 (.nii, magic 'n+1') is "
        "read (convert it, e.g. with nibabel)");
  if (magic != std::string_view("n+1\0", 4))
    r.fail("header field magic is not 'n+1' (a single-file NIfTI-1 image)");
}

std::array<int, 3> dimensions(const Header& h, const Reader& r) {
  const int rank = h.i16(40);
  if (rank < 1 || rank > 7) r.fail(fmt::format("header field dim[0] is {}, expected 1 to 7", rank));
  std::array<int, 3> dims{1, 1, 1};
  long long voxels = 1;
  for (int a = 1; a <= rank; ++a) {
    const int n = h.i16(40 + 2 * size_t(a));
    if (a > 3 && n > 1)
      r.fail(fmt::format("header field dim[{}] is {}: a label image has one 3-D volume", a, n));
    if (a <= 3 && (n < 1 || n > kNiftiMaxDim))
      r.fail(fmt::format("header field dim[{}] is {}, expected 1 to {}", a, n, kNiftiMaxDim));
    if (a <= 3) dims[size_t(a - 1)] = n, voxels *= n;
  }
  if (voxels > kNiftiMaxVoxels)
    r.fail(fmt::format("{} x {} x {} voxels is over the limit of {} (512^3)", dims[0], dims[1],
                       dims[2], kNiftiMaxVoxels));
  return dims;
}

// Metres per unit of the file's lengths (xyzt_units, bits 0-2).
double length_unit(const Header& h, const Reader& r) {
  switch (h.get<std::uint8_t>(123) & 0x07) {
    case 0:
      r.note("xyzt_units gives no length unit: millimetres assumed");
      return 1e-3;
    case 1:
      return 1.0;
    case 2:
      return 1e-3;
    case 3:
      return 1e-6;
  }
  r.fail(fmt::format("header field xyzt_units has length code {}, expected 0 to 3",
                     h.get<std::uint8_t>(123) & 0x07));
}

// The rotation of the quaternion (b, c, d), a from unit length, as the NIfTI standard says.
Eigen::Matrix3d quaternion_rotation(double b, double c, double d) {
  double a = 1.0 - (b * b + c * c + d * d);
  if (a < 1e-7) {  // a 180-degree rotation: (b, c, d) renormalised
    const double n = std::sqrt(b * b + c * c + d * d);
    b /= n, c /= n, d /= n, a = 0.0;
  } else {
    a = std::sqrt(a);
  }
  Eigen::Matrix3d R;
  R << a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c), 2 * (b * c + a * d),
      a * a + c * c - b * b - d * d, 2 * (c * d - a * b), 2 * (b * d - a * c), 2 * (c * d + a * b),
      a * a + d * d - c * c - b * b;
  return R;
}

void frame_from_header(const Header& h, const Reader& r, LabelImage& image) {
  const double unit = length_unit(h, r);
  const short sform = h.i16(254), qform = h.i16(252);
  Eigen::Matrix3d A;
  Vec3 b;
  if (sform > 0) {
    for (int row = 0; row < 3; ++row) {
      const char axis = "xyz"[row];
      for (int col = 0; col < 4; ++col) {
        const double v = r.finite(h, 280 + 16 * size_t(row) + 4 * size_t(col),
                                  fmt::format("srow_{}[{}]", axis, col));
        if (col < 3)
          A(row, col) = v;
        else
          b[row] = v;
      }
    }
  } else {
    Vec3 pixdim;
    for (int a = 0; a < 3; ++a)
      pixdim[a] = std::abs(r.finite(h, 80 + 4 * size_t(a), fmt::format("pixdim[{}]", a + 1)));
    if (qform > 0) {
      const double qb = r.finite(h, 256, "quatern_b"), qc = r.finite(h, 260, "quatern_c"),
                   qd = r.finite(h, 264, "quatern_d");
      if (qb * qb + qc * qc + qd * qd > 1.0 + 1e-6)
        r.fail(fmt::format("quatern_b, c, d ({}, {}, {}) are longer than 1: not a rotation", qb, qc,
                           qd));
      const double qfac = r.finite(h, 76, "pixdim[0] (qfac)") < 0.0 ? -1.0 : 1.0;
      A = quaternion_rotation(qb, qc, qd) *
          Vec3(pixdim[0], pixdim[1], qfac * pixdim[2]).asDiagonal();
      b = {r.finite(h, 268, "qoffset_x"), r.finite(h, 272, "qoffset_y"),
           r.finite(h, 276, "qoffset_z")};
    } else {
      r.note("no sform or qform (both codes 0): the frame is pixdim scaling only");
      A = pixdim.asDiagonal();
      b.setZero();
    }
  }
  image.axes = A * unit;
  image.origin = b * unit;
}

void check_voxel_sizes(const LabelImage& image, const Reader& r, const char* source) {
  const Vec3 mm = image.spacing() * 1e3;
  for (int a = 0; a < 3; ++a)
    if (!(mm[a] > kNiftiMinVoxelMm && mm[a] < kNiftiMaxVoxelMm))
      r.fail(
          fmt::format("voxel size along axis {} is {:g} mm (from the {}), expected between "
                      "{:g} and {:g} mm",
                      "ijk"[a], mm[a], source, kNiftiMinVoxelMm, kNiftiMaxVoxelMm));
  const double origin_mm = image.origin.cwiseAbs().maxCoeff() * 1e3;
  if (!(origin_mm <= kNiftiMaxOriginMm))
    r.fail(
        fmt::format("the first voxel lies {:g} mm from the scanner's origin (from the {}), "
                    "expected within {:g} mm",
                    origin_mm, source, kNiftiMaxOriginMm));
  const double det = image.axes.determinant() * 1e9;
  if (!(std::abs(det) > 1e-6 * mm.prod()))
    r.fail(fmt::format("the {} maps the voxel grid onto a plane (its axes are parallel)", source));
}

struct Datatype {
  int code, bytes;
  const char* name;
};
constexpr Datatype kDatatypes[] = {{2, 1, "uint8"},    {256, 1, "int8"},  {4, 2, "int16"},
                                   {512, 2, "uint16"}, {8, 4, "int32"},   {768, 4, "uint32"},
                                   {16, 4, "float32"}, {64, 8, "float64"}};

Datatype datatype(const Header& h, const Reader& r) {
  const int code = h.i16(70), bitpix = h.i16(72);
  for (const Datatype& t : kDatatypes)
    if (t.code == code) {
      if (bitpix != 8 * t.bytes)
        r.fail(fmt::format("header field bitpix is {}, expected {} for datatype {} ({})", bitpix,
                           8 * t.bytes, code, t.name));
      return t;
    }
  r.fail(
      fmt::format("header field datatype is {}, expected a label type: 2 uint8, 256 int8, 4 "
                  "int16, 512 uint16, 8 int32, 768 uint32, 16 float32 or 64 float64",
                  code));
}

// One voxel's label; floating-point values must be whole numbers within int32.
std::int32_t voxel(const Header& data, const Datatype& t, size_t at, size_t index,
                   const Reader& r) {
  double v = 0.0;
  switch (t.code) {
    case 2:
      return data.get<std::uint8_t>(at);
    case 256:
      return data.get<std::int8_t>(at);
    case 4:
      return data.get<std::int16_t>(at);
    case 512:
      return data.get<std::uint16_t>(at);
    case 8:
      return data.get<std::int32_t>(at);
    case 768:
      v = data.get<std::uint32_t>(at);
      break;
    case 16:
      v = data.get<float>(at);
      break;
    default:
      v = data.get<double>(at);
      break;
  }
  if (!(v == std::floor(v) && std::abs(v) <= 2147483647.0))
    r.fail(
        fmt::format("voxel {} holds {}, expected a whole-number label (a {} image is read as "
                    "labels, not intensities)",
                    index, v, t.name));
  return std::int32_t(v);
}

size_t voxel_offset(const Header& h, const Reader& r) {
  const double offset = r.finite(h, 108, "vox_offset");
  if (offset < double(kHeaderSize) || offset != std::floor(offset) || offset > 1e12)
    r.fail(fmt::format("header field vox_offset is {}, expected a whole number >= 348", offset));
  return size_t(offset);
}

}  // namespace

bool is_nifti_path(const std::filesystem::path& path) {
  const std::string s = path.filename().string();
  return s.ends_with(".nii") || s.ends_with(".nii.gz");
}

LabelImage parse_nifti_labels(std::string_view bytes, const std::string& name,
                              std::vector<std::string>* notes) {
  const Reader r{name, notes, io::is_gzip(bytes)};
  std::string inflated;
  if (r.gzip) {
    try {
      // The header first: it says how much data to expect, and no more is inflated.
      inflated = io::gunzip(bytes, kHeaderSize);
      const Header h = byte_order(inflated, r);
      const std::array<int, 3> d = dimensions(h, r);
      const size_t need = voxel_offset(h, r) +
                          size_t(d[0]) * size_t(d[1]) * size_t(d[2]) * size_t(datatype(h, r).bytes);
      inflated = io::gunzip(bytes, need);
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const MeshFileError*>(&e)) throw;
      r.fail(e.what());
    }
    bytes = inflated;
  }
  const Header h = byte_order(bytes, r);
  check_magic(h, r);
  LabelImage image;
  image.dims = dimensions(h, r);
  const Datatype type = datatype(h, r);
  const size_t offset = voxel_offset(h, r);
  frame_from_header(h, r, image);
  check_voxel_sizes(image, r, h.i16(254) > 0 ? "sform" : h.i16(252) > 0 ? "qform" : "pixdim");
  if (const float slope = h.f32(112); slope != 0.0f && slope != 1.0f)
    r.note(fmt::format("scl_slope {} ignored: label values are used as stored", slope));
  const size_t count = size_t(image.dims[0]) * size_t(image.dims[1]) * size_t(image.dims[2]);
  const size_t need = count * size_t(type.bytes);
  if (bytes.size() < offset || bytes.size() - offset < need)
    r.fail(fmt::format(
        "the voxel data ({} x {} x {} {}) needs {} bytes after vox_offset {}, the "
        "file holds {}{} (truncated, or wrong dim?)",
        image.dims[0], image.dims[1], image.dims[2], type.name, need, offset,
        bytes.size() > offset ? bytes.size() - offset : 0, r.gzip ? " once decompressed" : ""));
  const Header data{bytes.substr(offset), h.swap};
  image.labels.resize(count);
  for (size_t v = 0; v < count; ++v)
    image.labels[v] = voxel(data, type, v * size_t(type.bytes), v, r);
  return image;
}

LabelImage read_nifti_labels(const std::filesystem::path& path, std::vector<std::string>* notes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshFileError(path.string(), 0, 0, "cannot open the image file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_nifti_labels(s.str(), path.string(), notes);
}

}  // namespace phymul

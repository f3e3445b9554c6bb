// Internal to the VTK XML readers: the bytes of a binary DataArray (base64 or raw; a byte
// count header, or vtkZLibDataCompressor's block table and zlib blocks) and their values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace phymul::vtkxml {

// A problem in an array's data; `offset` is where in the stream's text it was found (npos:
// the array as a whole). The reader turns it into a MeshFileError naming the element.
struct DataError : std::runtime_error {
  DataError(const std::string& message, size_t at = std::string_view::npos)
      : std::runtime_error(message), offset(at) {}
  size_t offset;
};

// Decoded arrays larger than this are refused before anything is allocated for them.
constexpr std::uint64_t kMaxBytes = std::uint64_t(1) << 31;

// Bytes one after another from raw data or from base64 text (whitespace skipped; padding may
// end a chunk mid-stream, as VTK encodes an array's header and its data separately).
class ByteStream {
 public:
  ByteStream(std::string_view data, bool base64) : data_(data), base64_(base64) {}
  // The next n bytes (valid until the next call); a DataError if fewer are left.
  std::string_view take(std::uint64_t n, std::string_view what);
  // At most this many bytes are left (a guard before allocating).
  std::uint64_t most_left() const;
  size_t offset() const { return at_; }  // into the data, where the next byte comes from

 private:
  void decode_quad();
  std::string_view data_;
  bool base64_;
  size_t at_ = 0;
  std::string buffer_;   // decoded bytes (base64)
  std::string pending_;  // decoded beyond what was taken (base64)
};

// How the file stores binary arrays (VTKFile's header_type, byte_order and compressor).
struct Layout {
  int header_bytes = 4;  // UInt32 (VTK's default) or UInt64
  bool big_endian = false;
  bool zlib = false;
};

// The bytes of one array after its header: `expected` of them when the XML's counts say how
// many (a different count is a DataError), else whatever the header says (up to kMaxBytes).
std::string read_block(ByteStream& in, const Layout& layout, std::optional<std::uint64_t> expected);

enum class Scalar { int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32, float64 };

std::optional<Scalar> scalar_named(std::string_view vtk_name);  // "Int32", "Float64", ...
int size_of(Scalar s);
bool is_integer(Scalar s);

// Values of `bytes`, read as `type` in the file's byte order.
std::vector<double> to_reals(std::string_view bytes, Scalar type, bool big_endian);
std::vector<long long> to_integers(std::string_view bytes, Scalar type, bool big_endian);

}  // namespace phymul::vtkxml

// Decoding VTK XML binary arrays: base64, the byte-count or zlib block header, zlib blocks,
// and the values in either byte order.
#include "io/vtk_xml_data.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <bit>
#include <climits>
#include <cstring>

namespace phymul::vtkxml {
namespace {

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

// The largest inflation zlib achieves is about 1032:1; a header claiming more is corrupt.
constexpr std::uint64_t kMaxRatio = 1100;

std::uint64_t header_word(ByteStream& in, const Layout& layout, std::string_view what) {
  const std::string_view b = in.take(std::uint64_t(layout.header_bytes), what);
  std::uint64_t value = 0;
  for (int k = 0; k < layout.header_bytes; ++k) {
    const int from = layout.big_endian ? k : layout.header_bytes - 1 - k;
    value = (value << 8) | static_cast<unsigned char>(b[size_t(from)]);
  }
  return value;
}

void check_total(std::uint64_t total, std::optional<std::uint64_t> expected, size_t at) {
  if (total > kMaxBytes)
    throw DataError(fmt::format("its header claims {} bytes, over the limit of 2^31 bytes", total),
                    at);
  if (expected && total != *expected)
    throw DataError(fmt::format("its header says {} bytes of data, the counts in the XML need {}",
                                total, *expected),
                    at);
}

std::string inflate_blocks(ByteStream& in, const Layout& layout,
                           std::optional<std::uint64_t> expected) {
  const size_t at = in.offset();
  const std::uint64_t blocks = header_word(in, layout, "the zlib header's block count");
  const std::uint64_t size = header_word(in, layout, "the zlib header's block size");
  const std::uint64_t last = header_word(in, layout, "the zlib header's last block size");
  if (blocks > in.most_left() / std::uint64_t(layout.header_bytes))
    throw DataError(fmt::format("its zlib header claims {} blocks, more than the data can list "
                                "(truncated, or not zlib-compressed?)",
                                blocks),
                    at);
  if (blocks > 0 && (size == 0 || last > size))
    throw DataError(fmt::format("its zlib header's block size {} and last block size {} do not fit "
                                "(corrupt header?)",
                                size, last),
                    at);
  if (size > kMaxBytes) check_total(size, std::nullopt, at);
  const std::uint64_t total = blocks == 0 ? 0 : (blocks - 1) * size + (last == 0 ? size : last);
  check_total(total, expected, at);
  std::vector<std::uint64_t> compressed(blocks);
  for (std::uint64_t& c : compressed) c = header_word(in, layout, "a zlib block's size");
  std::string out(total, '\0');
  size_t done = 0;
  for (std::uint64_t k = 0; k < blocks; ++k) {
    const std::uint64_t want = k + 1 == blocks && last != 0 ? last : size;
    if (want > compressed[k] * kMaxRatio + 64)
      throw DataError(
          fmt::format("zlib block {} claims {} bytes from {} compressed ones, more than "
                      "zlib can inflate (corrupt header?)",
                      k, want, compressed[k]),
          at);
    const size_t block_at = in.offset();
    const std::string_view packed = in.take(compressed[k], fmt::format("zlib block {}", k));
    uLongf got = uLongf(want);
    const int r = uncompress(reinterpret_cast<Bytef*>(out.data() + done), &got,
                             reinterpret_cast<const Bytef*>(packed.data()), uLong(packed.size()));
    if (r != Z_OK || got != want)
      throw DataError(
          fmt::format("zlib block {} of {} does not inflate to its {} bytes ({})", k, blocks, want,
                      r == Z_OK          ? fmt::format("{} bytes", got)
                      : r == Z_BUF_ERROR ? "more data, or a cut stream"
                                         : zError(r)),
          block_at);
    done += size_t(want);
  }
  return out;
}

template <class T, class Out>
void convert(std::string_view bytes, bool big_endian, std::vector<Out>& out) {
  using Bits = std::conditional_t<
      sizeof(T) == 1, std::uint8_t,
      std::conditional_t<sizeof(T) == 2, std::uint16_t,
                         std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
  const bool swap = big_endian != (std::endian::native == std::endian::big);
  out.resize(bytes.size() / sizeof(T));
  for (size_t i = 0; i < out.size(); ++i) {
    Bits bits;
    std::memcpy(&bits, bytes.data() + i * sizeof(T), sizeof(T));
    if (swap) {
      if constexpr (sizeof(T) == 2) bits = __builtin_bswap16(bits);
      if constexpr (sizeof(T) == 4) bits = __builtin_bswap32(bits);
      if constexpr (sizeof(T) == 8) bits = __builtin_bswap64(bits);
    }
    const T value = std::bit_cast<T>(bits);
    if constexpr (std::is_same_v<T, std::uint64_t> && std::is_same_v<Out, long long>)
      out[i] = value > std::uint64_t(LLONG_MAX) ? LLONG_MAX : (long long)value;
    else
      out[i] = Out(value);
  }
}

template <class Out>
std::vector<Out> values(std::string_view bytes, Scalar type, bool big_endian) {
  std::vector<Out> out;
  switch (type) {
    case Scalar::int8:
      convert<std::int8_t>(bytes, big_endian, out);
      break;
    case Scalar::uint8:
      convert<std::uint8_t>(bytes, big_endian, out);
      break;
    case Scalar::int16:
      convert<std::int16_t>(bytes, big_endian, out);
      break;
    case Scalar::uint16:
      convert<std::uint16_t>(bytes, big_endian, out);
      break;
    case Scalar::int32:
      convert<std::int32_t>(bytes, big_endian, out);
      break;
    case Scalar::uint32:
      convert<std::uint32_t>(bytes, big_endian, out);
      break;
    case Scalar::int64:
      convert<std::int64_t>(bytes, big_endian, out);
      break;
    case Scalar::uint64:
      convert<std::uint64_t>(bytes, big_endian, out);
      break;
    case Scalar::float32:
      convert<float>(bytes, big_endian, out);
      break;
    case Scalar::float64:
      convert<double>(bytes, big_endian, out);
      break;
  }
  return out;
}

}  // namespace

void ByteStream::decode_quad() {
  int group[4], n = 0;
  while (n < 4) {
    while (at_ < data_.size() && is_space(data_[at_])) ++at_;
    if (at_ >= data_.size())
      throw DataError(n == 0 ? "the base64 data ends early (truncated?)"
                             : fmt::format("the base64 data ends inside a group of four "
                                           "characters, after {} (truncated?)",
                                           n),
                      at_);
    const char c = data_[at_];
    const int v = c == '=' && n >= 2 ? 64 : base64_value(c);
    if (v < 0 || (n == 3 && group[2] == 64 && v != 64))
      throw DataError(fmt::format("byte 0x{:02x} ('{}') is not base64",
                                  static_cast<unsigned char>(c), c >= 0x20 && c < 0x7f ? c : '?'),
                      at_);
    group[n++] = v;
    ++at_;
  }
  const unsigned bits = unsigned(group[0]) << 18 | unsigned(group[1]) << 12 |
                        unsigned(group[2] & 63) << 6 | unsigned(group[3] & 63);
  pending_ += char(bits >> 16);
  if (group[2] != 64) pending_ += char(bits >> 8 & 0xff);
  if (group[3] != 64) pending_ += char(bits & 0xff);
}

std::uint64_t ByteStream::most_left() const {
  const std::uint64_t rest = data_.size() - std::min(at_, data_.size());
  return base64_ ? rest / 4 * 3 + 3 + pending_.size() : rest;
}

std::string_view ByteStream::take(std::uint64_t n, std::string_view what) {
  if (n > most_left())
    throw DataError(fmt::format("{} needs {} bytes, at most {} are left (truncated, or a wrong "
                                "count?)",
                                what, n, most_left()),
                    at_);
  if (!base64_) {
    const std::string_view out = data_.substr(at_, size_t(n));
    at_ += size_t(n);
    return out;
  }
  buffer_.swap(pending_);
  pending_.clear();
  buffer_.reserve(size_t(n) + 3);
  while (buffer_.size() < n) {
    decode_quad();
    buffer_ += pending_;
    pending_.clear();
  }
  pending_.assign(buffer_, size_t(n), std::string::npos);
  buffer_.resize(size_t(n));
  return buffer_;
}

std::string read_block(ByteStream& in, const Layout& layout,
                       std::optional<std::uint64_t> expected) {
  if (layout.zlib) return inflate_blocks(in, layout, expected);
  const size_t at = in.offset();
  const std::uint64_t n = header_word(in, layout, "the array's byte count");
  check_total(n, expected, at);
  return std::string(in.take(n, "the array's data"));
}

std::optional<Scalar> scalar_named(std::string_view name) {
  static constexpr std::pair<std::string_view, Scalar> kNames[] = {
      {"Int8", Scalar::int8},       {"UInt8", Scalar::uint8},   {"Int16", Scalar::int16},
      {"UInt16", Scalar::uint16},   {"Int32", Scalar::int32},   {"UInt32", Scalar::uint32},
      {"Int64", Scalar::int64},     {"UInt64", Scalar::uint64}, {"Float32", Scalar::float32},
      {"Float64", Scalar::float64}, {"Char", Scalar::int8},     {"UChar", Scalar::uint8}};
  for (const auto& [n, s] : kNames)
    if (n == name) return s;
  return std::nullopt;
}

int size_of(Scalar s) {
  switch (s) {
    case Scalar::int8:
    case Scalar::uint8:
      return 1;
    case Scalar::int16:
    case Scalar::uint16:
      return 2;
    case Scalar::int32:
    case Scalar::uint32:
    case Scalar::float32:
      return 4;
    default:
      return 8;
  }
}

bool is_integer(Scalar s) { return s != Scalar::float32 && s != Scalar::float64; }

std::vector<double> to_reals(std::string_view bytes, Scalar type, bool big_endian) {
  return values<double>(bytes, type, big_endian);
}

std::vector<long long> to_integers(std::string_view bytes, Scalar type, bool big_endian) {
  return values<long long>(bytes, type, big_endian);
}

}  // namespace phymul::vtkxml

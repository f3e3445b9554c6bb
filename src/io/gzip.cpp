#include "io/gzip.hpp"

#include <zlib.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace phymul::io {

bool is_gzip(std::string_view bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f &&
         static_cast<unsigned char>(bytes[1]) == 0x8b;
}

std::string gunzip(std::string_view bytes, size_t limit) {
  z_stream z{};
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("zlib: cannot start");
  std::string out;
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = uInt(std::min<size_t>(bytes.size(), 1u << 30));
  int rc = Z_OK;
  while (out.size() < limit && rc == Z_OK) {
    // Grow in steps of at most 64 MiB, never past the limit.
    const size_t chunk = std::min<size_t>(limit - out.size(), size_t(64) << 20);
    const size_t at = out.size();
    out.resize(at + chunk);
    z.next_out = reinterpret_cast<Bytef*>(out.data() + at);
    z.avail_out = uInt(chunk);
    rc = inflate(&z, Z_NO_FLUSH);
    out.resize(at + chunk - z.avail_out);
    // No progress possible: the input ended (truncated), and what there is is returned.
    if (rc == Z_BUF_ERROR) break;
  }
  const std::string reason = z.msg ? z.msg : "";
  inflateEnd(&z);
  if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
    throw std::runtime_error("corrupt gzip data (zlib: " + (reason.empty() ? "error" : reason) +
                             ")");
  return out;
}

}  // namespace phymul::io

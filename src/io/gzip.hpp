// gzip decompression (zlib) with a cap on the output: a small file cannot expand into
// gigabytes before its header has been checked.
#pragma once

#include <string>
#include <string_view>

namespace phymul::io {

// True when the bytes start with gzip's magic number (1f 8b).
bool is_gzip(std::string_view bytes);

// The first `limit` bytes of the decompressed data, or all of it when shorter. Throws
// std::runtime_error with zlib's reason for corrupt data; a truncated stream gives what
// could be decompressed (the caller checks the size it needs).
std::string gunzip(std::string_view bytes, size_t limit);

}  // namespace phymul::io

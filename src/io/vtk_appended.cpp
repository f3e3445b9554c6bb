#include "io/vtk_appended.hpp"

#include <fmt/format.h>

#include <bit>
#include <ostream>

namespace phymul {

// The header says LittleEndian and the bytes are the machine's own.
static_assert(std::endian::native == std::endian::little,
              "the binary .vtu writer copies memory as is: little-endian machines only");

void AppendedData::add_bytes(std::ostream& os, std::string_view type, std::string_view escaped_name,
                             int components, std::span<const std::byte> bytes) {
  const std::string declared =
      components > 0 ? fmt::format(" NumberOfComponents=\"{}\"", components) : "";
  os << fmt::format(
      "        <DataArray type=\"{}\" Name=\"{}\"{} format=\"appended\" offset=\"{}\"/>\n", type,
      escaped_name, declared, offset_);
  blocks_.push_back(bytes);
  offset_ += sizeof(std::uint64_t) + bytes.size();
}

void AppendedData::write(std::ostream& os) const {
  // The underscore marks the start of the data; readers (meshio) drop the newline after it.
  os << "  <AppendedData encoding=\"raw\">\n   _";
  for (const std::span<const std::byte> block : blocks_) {
    const std::uint64_t count = block.size();
    os.write(reinterpret_cast<const char*>(&count), sizeof count);
    os.write(reinterpret_cast<const char*>(block.data()), std::streamsize(block.size()));
  }
  os << "\n  </AppendedData>\n";
}

}  // namespace phymul

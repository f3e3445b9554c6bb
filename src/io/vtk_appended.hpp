// VTK XML appended raw data, the `binary` VtuEncoding: each DataArray tag gives its offset
// into one block after the XML, where the array's bytes follow their UInt64 count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <span>
#include <string_view>
#include <vector>

namespace phymul {

class AppendedData {
 public:
  // The array's DataArray tag (components 0: none declared, VTK's default of 1); its bytes
  // are written by write() from `values`, which must stay alive until then (no copy).
  template <class T>
  void add(std::ostream& os, std::string_view type, std::string_view escaped_name, int components,
           std::span<const T> values) {
    add_bytes(os, type, escaped_name, components, std::as_bytes(values));
  }
  // The <AppendedData> element: goes after </UnstructuredGrid>, before </VTKFile>.
  void write(std::ostream& os) const;

 private:
  void add_bytes(std::ostream& os, std::string_view type, std::string_view escaped_name,
                 int components, std::span<const std::byte> bytes);
  std::vector<std::span<const std::byte>> blocks_;
  std::uint64_t offset_ = 0;  // of the next block
};

}  // namespace phymul

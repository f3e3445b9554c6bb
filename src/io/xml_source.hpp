// Internal to the PML and LML readers: an XML document (pugixml) that knows where each of
// its elements is in the text, so that every problem names the file, line, column and element.
#pragma once

#include <optional>
#include <pugixml.hpp>
#include <string>
#include <string_view>

#include "phymul/mesh_io.hpp"

namespace phymul::xml {

class Source {
 public:
  // Parses `text`; a MeshFileError at the place the XML breaks (not XML, truncated).
  Source(std::string_view text, std::string name);

  const pugi::xml_document& document() const { return doc_; }
  const std::string& name() const { return name_; }

  // The line and column (1-based) of an element's '<'.
  std::pair<int, int> where(const pugi::xml_node& node) const;
  // "file:line:column: message", as a note names a place.
  std::string at(const pugi::xml_node& node, const std::string& message) const;
  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& message) const;

  // A required attribute: a finite number; a whole number in [min, max].
  double number(const pugi::xml_node& node, const char* attribute) const;
  long long integer(const pugi::xml_node& node, const char* attribute, long long min,
                    long long max) const;

 private:
  std::string_view text_;
  std::string name_;
  pugi::xml_document doc_;
};

// "<atomProperties>", as messages name elements.
std::string tag(const pugi::xml_node& node);
// The text trimmed of spaces, tabs and newlines at both ends.
std::string_view trim(std::string_view text);
// A finite decimal number, the whole text; nullopt otherwise.
std::optional<double> to_number(std::string_view text);

}  // namespace phymul::xml

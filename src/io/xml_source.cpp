#include "io/xml_source.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <optional>

namespace phymul::xml {
namespace {

// Line and column (1-based) of a byte offset in `text`.
std::pair<int, int> line_column(std::string_view text, size_t offset) {
  offset = std::min(offset, text.size());
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < offset; ++i)
    if (text[i] == '\n') ++line, line_start = i + 1;
  return {line, int(offset - line_start) + 1};
}

std::string quoted(std::string_view text) {
  if (text.size() > 24) return fmt::format("'{}...'", text.substr(0, 21));
  return fmt::format("'{}'", text);
}

}  // namespace

std::string tag(const pugi::xml_node& node) { return fmt::format("<{}>", node.name()); }

std::string_view trim(std::string_view text) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!text.empty() && space(text.front())) text.remove_prefix(1);
  while (!text.empty() && space(text.back())) text.remove_suffix(1);
  return text;
}

std::optional<double> to_number(std::string_view text) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);  // CamiTK writes "+1e-3"
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc{} || end != text.data() + text.size() ||
      !std::isfinite(value))
    return std::nullopt;
  return value;
}

Source::Source(std::string_view text, std::string name) : text_(text), name_(std::move(name)) {
  // No conversion of the encoding, so that offsets are offsets in `text`.
  const pugi::xml_parse_result result =
      doc_.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!result) {
    const size_t offset = size_t(std::max<ptrdiff_t>(result.offset, 0));
    const auto [line, column] = line_column(text_, offset);
    // pugixml reports a file cut short as a mismatch at its end.
    const size_t end = text_.find_last_not_of(" \t\r\n");
    const bool cut = (end == std::string_view::npos || offset >= end) &&
                     result.status == pugi::status_end_element_mismatch;
    throw MeshFileError(name_, line, column,
                        cut ? "not well-formed XML: the file ends before its elements close "
                              "(truncated?)"
                            : fmt::format("not well-formed XML: {}", result.description()));
  }
}

std::pair<int, int> Source::where(const pugi::xml_node& node) const {
  const ptrdiff_t offset = node.offset_debug();
  if (offset <= 0) return {0, 0};
  return line_column(text_, size_t(offset - 1));  // the name follows the '<'
}

std::string Source::at(const pugi::xml_node& node, const std::string& message) const {
  const auto [line, column] = where(node);
  return line > 0 ? fmt::format("{}:{}:{}: {}", name_, line, column, message)
                  : fmt::format("{}: {}", name_, message);
}

void Source::fail(const pugi::xml_node& node, const std::string& message) const {
  const auto [line, column] = where(node);
  throw MeshFileError(name_, line, column, message);
}

double Source::number(const pugi::xml_node& node, const char* attribute) const {
  const pugi::xml_attribute a = node.attribute(attribute);
  if (!a) fail(node, fmt::format("{} needs the attribute '{}' (a number)", tag(node), attribute));
  const auto value = to_number(a.value());
  if (!value)
    fail(node, fmt::format("{} attribute '{}' must be a finite number, found {}", tag(node),
                           attribute, quoted(a.value())));
  return *value;
}

long long Source::integer(const pugi::xml_node& node, const char* attribute, long long min,
                          long long max) const {
  const pugi::xml_attribute a = node.attribute(attribute);
  if (!a)
    fail(node, fmt::format("{} needs the attribute '{}' (a whole number)", tag(node), attribute));
  const std::string_view text = trim(a.value());
  long long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc{} || end != text.data() + text.size())
    fail(node, fmt::format("{} attribute '{}' must be a whole number, found {}", tag(node),
                           attribute, quoted(a.value())));
  if (value < min || value > max)
    fail(node, fmt::format("{} attribute '{}' must be in [{}, {}], found {}", tag(node), attribute,
                           min, max, value));
  return value;
}

}  // namespace phymul::xml

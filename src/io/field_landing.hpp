// Where a field of the parameter table lands in the Scene: the member of its section's Spec,
// and that member's default as scene text, so that a field's default is the struct's and is
// declared once (parameter_table.cpp's `.lands = lands(&SimulationSpec::dt)`).
#pragma once

#include <fmt/format.h>

#include <any>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "phymul/scene_words.hpp"
#include "phymul/schema.hpp"

namespace phymul::io {

struct Landing {
  std::any member;                          // a FieldMember<Spec>; empty: read by hand
  std::optional<std::string> default_text;  // Spec{}'s value as scene text; none when empty
  std::vector<std::string_view> words;      // a choice's
};

namespace landing {

// The shortest text that reads back to v, exponents without padding: "1e-6", "0.02".
inline std::optional<std::string> text(double v) {
  std::string out = fmt::format("{}", v);
  if (const auto e = out.find("e-0"); e != std::string::npos) out.erase(e + 2, 1);
  return out;
}
inline std::optional<std::string> text(const std::optional<double>& v) {
  return v ? text(*v) : std::nullopt;
}
inline std::optional<std::string> text(int v) { return fmt::format("{}", v); }
inline std::optional<std::string> text(long v) { return fmt::format("{}", v); }
inline std::optional<std::string> text(bool v) { return v ? "true" : "false"; }
inline std::optional<std::string> text(const Eigen::Vector3d& v) {
  return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z());
}
inline std::optional<std::string> text(const std::array<int, 3>& v) {
  return fmt::format("[{}, {}, {}]", v[0], v[1], v[2]);
}
inline std::optional<std::string> text(const std::array<bool, 3>& axes) {
  std::string out;
  for (int k = 0; k < 3; ++k)
    if (axes[size_t(k)]) out += char('x' + k);
  return out.empty() ? std::nullopt : std::optional(out);
}
inline std::optional<std::string> text(const std::vector<int>& v) {
  if (v.empty()) return std::nullopt;
  std::string out;
  for (int i : v) out += fmt::format("{}{}", out.empty() ? "[" : ", ", i);
  return out + "]";
}
inline std::optional<std::string> text(const std::string& v) {
  return v.empty() ? std::nullopt : std::optional(v);
}
inline std::optional<std::string> text(const Schedule&) { return std::nullopt; }
inline std::optional<std::string> text(const NodeSelector&) { return std::nullopt; }

}  // namespace landing

// A field whose words name the values of `member` (an enum, or an axis index).
template <class Spec, class Value, size_t N>
Landing lands(Value Spec::*member, const std::array<SceneWord<Value>, N>& words) {
  ChoiceMember<Spec> choice;
  choice.get = [member, &words](const Spec& s) { return word_of(words, s.*member); };
  choice.set = [member, &words](Spec& s, std::string_view word) {
    s.*member = *value_of(words, word);
  };
  for (const auto& w : words) choice.words.push_back(w.first);
  Landing out;
  out.words = choice.words;
  out.default_text = std::string(word_of(words, Spec{}.*member));
  out.member = FieldMember<Spec>(std::move(choice));
  return out;
}

template <class Spec, class T>
Landing lands(T Spec::*member) {
  if constexpr (std::is_enum_v<T>) {
    return lands(member, SceneWords<T>::words);
  } else {
    Landing out;
    out.member = FieldMember<Spec>(member);
    out.default_text = landing::text(Spec{}.*member);
    return out;
  }
}

}  // namespace phymul::io

// Each scene field is declared once, with where it lands in the Scene: these checks read every
// such field from YAML through the scene reader and find its value in that member, and find
// the member at its Spec's default when the field is absent.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "io/parameter_table.hpp"
#include "io/scene_reader.hpp"

namespace phymul::io {
namespace {

// A value inside the field's range, away from `avoid` (the Spec's default).
double sample_number(const Parameter& p, double avoid) {
  const Range& r = p.range;
  double v = r.min && r.max ? 0.5 * (*r.min + *r.max)
             : r.min        ? *r.min + 1.5
             : r.max        ? *r.max - 1.5
                            : 2.5;
  if (v == avoid) v = r.max ? 0.5 * (v + *r.max) : v + 1.0;
  if (p.kind == Kind::integer || p.kind == Kind::integer_vector || p.kind == Kind::integers) {
    v = std::ceil(v);
    if (v == avoid || (r.max && v > *r.max)) v = std::floor(v) - 1.0;
  }
  return v;
}

std::string other_word(const Parameter& p, std::string_view avoid) {
  for (const auto word : p.choices)
    if (word != avoid) return std::string(word);
  return std::string(avoid);
}

// The YAML text of a sample for `p`, and checks that `member` took it.
template <class Spec, class Member>
std::string sample(const Parameter& p, const Member& member) {
  static const Spec defaults{};
  if constexpr (std::is_same_v<Member, ChoiceMember<Spec>>) {
    return other_word(p, member.get(defaults));
  } else {
    using T = std::decay_t<decltype(defaults.*member)>;
    if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int> || std::is_same_v<T, long>)
      return fmt::format("{}", sample_number(p, double(defaults.*member)));
    else if constexpr (std::is_same_v<T, std::optional<double>>)
      return fmt::format("{}", sample_number(p, (defaults.*member).value_or(NAN)));
    else if constexpr (std::is_same_v<T, bool>)
      return defaults.*member ? "false" : "true";
    else if constexpr (std::is_same_v<T, Eigen::Vector3d> || std::is_same_v<T, std::array<int, 3>>)
      return fmt::format("[{0}, {0}, {0}]", sample_number(p, double((defaults.*member)[0])));
    else if constexpr (std::is_same_v<T, std::array<bool, 3>>)
      return "xz";
    else if constexpr (std::is_same_v<T, std::vector<int>>)
      return "[1, 2]";
    else if constexpr (std::is_same_v<T, std::string>)
      return p.kind == Kind::choice ? other_word(p, defaults.*member)
             : p.kind == Kind::path ? "organ.vtk"
                                    : "organ_2";
    else if constexpr (std::is_same_v<T, NodeSelector>)
      return "\"1-3\"";
    else if (p.kind == Kind::schedule)
      return "[{t: 0, value: [0.5, 0.5, 0.5]}, {t: 1, value: [0.25, 0.25, 0.25]}]";
    else if (p.kind == Kind::scalar_schedule)
      return "[{t: 0, value: 0.5}, {t: 1, value: 0.25}]";
    else if (p.kind == Kind::vector)
      return "[0.5, 0.5, 0.5]";
    else
      return "0.5";
  }
}

// What the member holds, as text to compare with the sample (the same formatting).
template <class Spec, class Member>
std::string landed(const Parameter& p, const Spec& spec, const Member& member) {
  if constexpr (std::is_same_v<Member, ChoiceMember<Spec>>) {
    return std::string(member.get(spec));
  } else {
    const auto& v = spec.*member;
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int> || std::is_same_v<T, long>)
      return fmt::format("{}", double(v));
    else if constexpr (std::is_same_v<T, std::optional<double>>)
      return v ? fmt::format("{}", *v) : "absent";
    else if constexpr (std::is_same_v<T, bool>)
      return v ? "true" : "false";
    else if constexpr (std::is_same_v<T, Eigen::Vector3d> || std::is_same_v<T, std::array<int, 3>>)
      return fmt::format("[{}, {}, {}]", double(v[0]), double(v[1]), double(v[2]));
    else if constexpr (std::is_same_v<T, std::array<bool, 3>>)
      return std::string(v[0] ? "x" : "") + (v[1] ? "y" : "") + (v[2] ? "z" : "");
    else if constexpr (std::is_same_v<T, std::vector<int>>)
      return fmt::format("[{}]", fmt::join(v, ", "));
    else if constexpr (std::is_same_v<T, std::string>)
      return v;
    else if constexpr (std::is_same_v<T, NodeSelector>)
      return v.indices.empty() ? std::string("all")
                               : fmt::format("\"{}-{}\"", v.indices.front(), v.indices.back());
    else {
      std::string out = "[";
      const bool scalar = p.kind == Kind::scalar_schedule || p.kind == Kind::quantity;
      for (size_t k = 0; k < v.times.size(); ++k) {
        const Eigen::Vector3d& x = v.values[k];
        out += fmt::format(
            "{}{{t: {}, value: {}}}", k ? ", " : "", v.times[k],
            scalar ? fmt::format("{}", x.x()) : fmt::format("[{}, {}, {}]", x.x(), x.y(), x.z()));
      }
      out += "]";
      if (v.times.size() == 1 && v.times[0] == 0.0)  // a constant
        return scalar
                   ? fmt::format("{}", v.values[0].x())
                   : fmt::format("[{}, {}, {}]", v.values[0].x(), v.values[0].y(), v.values[0].z());
      return out;
    }
  }
}

// The siblings `p` needs to apply (its `when`), as YAML lines.
std::string conditions(const Parameter& p) {
  std::string out;
  for (const auto& c : p.when) out += fmt::format("{}: {}\n", c.key, c.values.front());
  return out;
}

template <class Spec>
int check_section(std::string_view section) {
  int checked = 0;
  for (const Parameter* p : section_parameters(section)) {
    const auto* member = std::any_cast<FieldMember<Spec>>(&p->lands.member);
    if (!member) continue;
    SCOPED_TRACE(fmt::format("{}.{}", section, p->name));
    const std::string text =
        std::visit([&](const auto& m) { return sample<Spec>(*p, m); }, *member);
    const std::string yaml = conditions(*p) + fmt::format("{}: {}\n", p->name, text);
    SceneContext context("fields.yaml");
    SectionReader reader(context, YAML::Load(yaml), section, "'here'", {});
    Spec spec{};
    reader.read_fields(spec);
    EXPECT_TRUE(reader.given(p->name)) << yaml;
    EXPECT_EQ(std::visit([&](const auto& m) { return landed(*p, spec, m); }, *member), text)
        << yaml;
    // Absent, the member keeps Spec's default, which is what the table documents.
    const std::string siblings = conditions(*p);
    SectionReader empty(context, YAML::Load(siblings.empty() ? "{}" : siblings), section, "'here'",
                        {});
    Spec absent{};
    empty.read_fields(absent);
    static const Spec defaults{};
    EXPECT_EQ(std::visit([&](const auto& m) { return landed(*p, absent, m); }, *member),
              std::visit([&](const auto& m) { return landed(*p, defaults, m); }, *member));
    ++checked;
  }
  return checked;
}

TEST(FieldLanding, EveryFieldDeclaredWithItsMemberLandsThereAndAbsentKeepsTheDefault) {
  int checked = check_section<SimulationSpec>("simulation") + check_section<ObjectSpec>("object") +
                check_section<MeshSpec>("mesh") + check_section<MeshTransform>("transform") +
                check_section<MeshTransform>("rotation") + check_section<MaterialSpec>("material") +
                check_section<LoadSpec>("load") + check_section<PressureSpec>("load") +
                check_section<PressureSpec>("pressure_cylinder") +
                check_section<ConstraintSpec>("constraint") + check_section<MotionSpec>("motion") +
                check_section<FibreSpec>("fibres") + check_section<LinkSpec>("link") +
                check_section<ObstacleSpec>("obstacle") + check_section<OutputSpec>("output") +
                check_section<NeedleSpec>("needle") +
                check_section<NeedleTissueSpec>("needle_tissue") +
                check_section<NeedleTargetSpec>("needle_target");
  int declared = 0;
  for (const auto& p : parameter_table()) declared += p.lands.member.has_value();
  EXPECT_EQ(checked, declared) << "a Spec whose fields this test does not read";
  EXPECT_GT(declared, 100);
}

// A field the reader reads by hand (a check or a conversion beside its value) has no member;
// the others give no default of their own: the Spec's is the one.
TEST(FieldLanding, DefaultsOfLandingFieldsAreTheirSpecsAndChoicesTheirWords) {
  const Parameter* dt = find_parameter("simulation", "dt_safety");
  ASSERT_NE(dt, nullptr);
  EXPECT_EQ(dt->default_value, fmt::format("{}", SimulationSpec{}.dt_safety));
  const Parameter* relaxation = find_parameter("simulation", "relaxation");
  ASSERT_NE(relaxation, nullptr);
  ASSERT_EQ(relaxation->choices.size(), SceneWords<Relaxation>::words.size());
  for (size_t k = 0; k < relaxation->choices.size(); ++k)
    EXPECT_EQ(relaxation->choices[k], SceneWords<Relaxation>::words[k].first);
  EXPECT_EQ(relaxation->default_value, scene_word(SimulationSpec{}.relaxation));
  const Parameter* axis = find_parameter("material", "calibration_axis");
  ASSERT_NE(axis, nullptr);
  EXPECT_EQ(axis->default_value, "z");
}

}  // namespace
}  // namespace phymul::io

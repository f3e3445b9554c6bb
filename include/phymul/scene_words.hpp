// The words a scene file spells each enum of the Scene with, declared once: the scene reader,
// the parameter table (its choices and defaults), the reference and the Python module all
// read them from here.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "phymul/scene.hpp"

namespace phymul {

template <class Value>
using SceneWord = std::pair<std::string_view, Value>;

// Specialised for each enum a scene field holds: `words`, in the order the reference lists them.
template <class Enum>
struct SceneWords;

template <>
struct SceneWords<DtEstimate> {
  static constexpr std::array words{SceneWord<DtEstimate>{"gershgorin", DtEstimate::gershgorin},
                                    SceneWord<DtEstimate>{"power", DtEstimate::power}};
};

template <>
struct SceneWords<Integrator> {
  static constexpr std::array words{SceneWord<Integrator>{"verlet", Integrator::verlet},
                                    SceneWord<Integrator>{"newton-cotes", Integrator::newton_cotes},
                                    SceneWord<Integrator>{"implicit", Integrator::implicit}};
};

template <>
struct SceneWords<SolveMode> {
  static constexpr std::array words{SceneWord<SolveMode>{"dynamic", SolveMode::dynamic},
                                    SceneWord<SolveMode>{"static", SolveMode::static_equilibrium}};
};

template <>
struct SceneWords<Relaxation> {
  static constexpr std::array words{SceneWord<Relaxation>{"kinetic", Relaxation::kinetic},
                                    SceneWord<Relaxation>{"fire", Relaxation::fire},
                                    SceneWord<Relaxation>{"viscous", Relaxation::viscous}};
};

template <>
struct SceneWords<StaticSolver> {
  static constexpr std::array words{SceneWord<StaticSolver>{"relaxation", StaticSolver::relaxation},
                                    SceneWord<StaticSolver>{"newton", StaticSolver::newton},
                                    SceneWord<StaticSolver>{"implicit", StaticSolver::implicit}};
};

// A generated box's cells; the other cell types are not a generator's choice.
template <>
struct SceneWords<CellType> {
  static constexpr std::array words{SceneWord<CellType>{"hexa", CellType::hexa},
                                    SceneWord<CellType>{"tetra", CellType::tetra}};
};

template <>
struct SceneWords<ElasticModel> {
  static constexpr std::array words{
      SceneWord<ElasticModel>{"shape-memory", ElasticModel::shape_memory},
      SceneWord<ElasticModel>{"fem", ElasticModel::fem}};
};

template <>
struct SceneWords<fem::Law> {
  static constexpr std::array words{SceneWord<fem::Law>{"neo-hookean", fem::Law::neo_hookean},
                                    SceneWord<fem::Law>{"linear", fem::Law::linear}};
};

template <>
struct SceneWords<fem::HexaElement> {
  static constexpr std::array words{
      SceneWord<fem::HexaElement>{"mean-dilatation", fem::HexaElement::mean_dilatation},
      SceneWord<fem::HexaElement>{"incompatible-modes", fem::HexaElement::incompatible_modes}};
};

template <>
struct SceneWords<FrameMode> {
  static constexpr std::array words{SceneWord<FrameMode>{"polar", FrameMode::polar},
                                    SceneWord<FrameMode>{"frame", FrameMode::frame}};
};

template <>
struct SceneWords<ObjectType> {
  static constexpr std::array words{SceneWord<ObjectType>{"elastic", ObjectType::elastic},
                                    SceneWord<ObjectType>{"rigid", ObjectType::rigid},
                                    SceneWord<ObjectType>{"active", ObjectType::active}};
};

template <>
struct SceneWords<ConstraintSpec::Kind> {
  using Kind = ConstraintSpec::Kind;
  static constexpr std::array words{SceneWord<Kind>{"fixed", Kind::fixed},
                                    SceneWord<Kind>{"displacement", Kind::displacement},
                                    SceneWord<Kind>{"spring", Kind::spring}};
};

template <>
struct SceneWords<ObstacleShape> {
  static constexpr std::array words{SceneWord<ObstacleShape>{"plane", ObstacleShape::plane},
                                    SceneWord<ObstacleShape>{"sphere", ObstacleShape::sphere},
                                    SceneWord<ObstacleShape>{"capsule", ObstacleShape::capsule},
                                    SceneWord<ObstacleShape>{"probe", ObstacleShape::probe}};
};

template <>
struct SceneWords<VtuEncoding> {
  static constexpr std::array words{SceneWord<VtuEncoding>{"ascii", VtuEncoding::ascii},
                                    SceneWord<VtuEncoding>{"binary", VtuEncoding::binary}};
};

// An axis index (0 x, 1 y, 2 z) as a scene spells it: the calibration's compression axis.
inline constexpr std::array kAxisWords{SceneWord<int>{"x", 0}, SceneWord<int>{"y", 1},
                                       SceneWord<int>{"z", 2}};

// The word of `value`; "" when `words` has none (a value no scene can give).
template <class Value, size_t N>
constexpr std::string_view word_of(const std::array<SceneWord<Value>, N>& words, Value value) {
  for (const auto& [word, v] : words)
    if (v == value) return word;
  return {};
}

template <class Enum>
constexpr std::string_view scene_word(Enum value) {
  return word_of(SceneWords<Enum>::words, value);
}

template <class Value, size_t N>
constexpr std::optional<Value> value_of(const std::array<SceneWord<Value>, N>& words,
                                        std::string_view word) {
  for (const auto& [w, v] : words)
    if (w == word) return v;
  return std::nullopt;
}

template <class Enum>
constexpr std::optional<Enum> scene_value(std::string_view word) {
  return value_of(SceneWords<Enum>::words, word);
}

// The words of an enum, for a command-line option that takes the scene's (CLI::IsMember).
template <class Enum>
std::vector<std::string> scene_words() {
  std::vector<std::string> out;
  for (const auto& [word, value] : SceneWords<Enum>::words) out.emplace_back(word);
  return out;
}

}  // namespace phymul

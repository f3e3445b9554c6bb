// Scene keys of organs in their environment: object types, motion, fibres, stitches and
// doubled nodes, read and compiled.
#include <gtest/gtest.h>

#include "phymul/model.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {
namespace {

const char* kScene = R"(objects:
  - name: bone
    type: rigid
    mesh: {generator: box, size: [2 cm, 2 cm, 1 cm], cells: [2, 2, 1], center: [0, 0, 2.5 cm]}
    material: {density: 1.9 g/cm^3}
    motion:
      translation: [{t: 0, value: [0, 0, 0]}, {t: 1 s, value: [0, 0, 5 mm]}]
  - name: muscle
    type: active
    mesh: {generator: box, size: [2 cm, 2 cm, 4 cm], cells: [2, 2, 4]}
    material: {stiffness: 30 N/m, density: 1060 kg/m^3}
    fibres:
      direction: [0, 0, 2]
      max_contraction: 0.25
      activation: [{t: 0, a: 0}, {t: 200 ms, a: 0.5}]
  - name: fat
    mesh: {generator: box, size: [2 cm, 2 cm, 1 cm], cells: [2, 2, 1], center: [0, 0, -2.5 cm]}
    material: {stiffness: 5 N/m, density: 900 kg/m^3}
stitches:
  - {object: fat, with: muscle, nodes: "12, 14", with_nodes: bottom, tolerance: 0.01 mm}
doubled:
  - {object: muscle, with: bone, nodes: top}
)";

TEST(SceneComponents, ReadsTypesMotionFibresAndLinks) {
  const Scene scene = parse_scene(kScene, "organs.yaml");
  ASSERT_EQ(scene.objects.size(), 3u);
  EXPECT_EQ(scene.objects[0].type, ObjectType::rigid);
  ASSERT_TRUE(scene.objects[0].motion.has_value());
  EXPECT_EQ(scene.objects[0].motion->translation.at(0.5), Vec3(0, 0, 0.0025));
  EXPECT_TRUE(scene.objects[0].motion->rotation.empty());
  EXPECT_DOUBLE_EQ(*scene.objects[0].material.density, 1900.0);
  EXPECT_EQ(scene.objects[1].type, ObjectType::active);
  EXPECT_EQ(scene.objects[1].fibres.direction, Vec3(0, 0, 2));
  EXPECT_DOUBLE_EQ(scene.objects[1].fibres.max_contraction, 0.25);
  EXPECT_FALSE(scene.objects[1].fibres.stiffness.has_value());
  EXPECT_DOUBLE_EQ(scene.objects[1].fibres.activation.at(0.1).x(), 0.25);
  EXPECT_EQ(scene.objects[2].type, ObjectType::elastic);
  ASSERT_EQ(scene.stitches.size(), 1u);
  EXPECT_EQ(scene.stitches[0].with, "muscle");
  EXPECT_DOUBLE_EQ(scene.stitches[0].tolerance, 1e-5);
  ASSERT_EQ(scene.doubled.size(), 1u);
  EXPECT_DOUBLE_EQ(scene.doubled[0].tolerance, 1e-6);  // the default
}

TEST(SceneComponents, CompilesALimitedStitchAndTheDoubledFace) {
  const Model model = compile_scene(parse_scene(kScene, "organs.yaml"));
  // Two listed nodes of the fat's top face are shared with the muscle: 3 boxes of 18, 45
  // and 18 nodes less 2 merged.
  EXPECT_EQ(model.node_count(), 18 + 45 + 18 - 2);
  const auto& fat = model.components[2].nodes;
  const auto& muscle = model.components[1].nodes;
  for (int local : {12, 14})
    EXPECT_NE(std::find(muscle.begin(), muscle.end(), fat[local]), muscle.end());
  // The muscle's top face (9 nodes) is doubled with the bone: it moves with the bone.
  EXPECT_EQ(model.doubled_pairs.size(), 9u);
  EXPECT_EQ(model.rigid_bodies.size(), 1u);
  EXPECT_TRUE(model.rigid_bodies[0].driven);
  EXPECT_EQ(model.rigid_bodies[0].nodes.size(), 18u + 9u);
  EXPECT_EQ(model.doubled.rows(), 0);  // every group rides on the bone
  // Fibres: 9 lines of 5 nodes along z, the material's stiffness.
  ASSERT_EQ(model.fibres.size(), 1u);
  EXPECT_EQ(model.fibres[0].polylines.rows(), 9);
  EXPECT_DOUBLE_EQ(model.fibres[0].stiffness, 30.0);
  EXPECT_EQ(model.components[1].kind, ObjectType::active);
}

}  // namespace
}  // namespace phymul

// `phymul run` writes frames, a series, monitors and a report that real readers accept.
#include <gtest/gtest.h>

#include <fstream>

#include "support/process.hpp"

namespace phymul {
namespace {

using testing::run_command;

constexpr const char* kScene = R"(simulation:
  dt: auto
  duration: 0.2 s
  gravity: [0, 0, -9.81]
  damping: 5 1/s
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [2, 2, 2]}
    material: {stiffness: 5 N/m, density: 1000 kg/m^3}
    volume_constraint: true
constraints:
  - {type: fixed, object: jelly, nodes: top}
output:
  interval: 0.05 s
)";

// Reads the series with meshio and checks each frame against its own fields:
// displacement = points - rest points, and prints a summary line to parse.
constexpr const char* kReader = R"(import json, sys, os, xml.etree.ElementTree as ET
import meshio, numpy as np
d = sys.argv[1]
root = ET.parse(os.path.join(d, 'jelly.pvd')).getroot()
sets = root.find('Collection').findall('DataSet')
rest = meshio.read(os.path.join(d, sets[0].get('file'))).points
worst = 0.0
for s in sets:
    m = meshio.read(os.path.join(d, s.get('file')))
    u = m.point_data['displacement']
    worst = max(worst, float(np.abs(m.points - rest - u).max()))
    assert m.cells[0].type == 'hexahedron' and len(m.cells[0].data) == 8
    assert set(np.ravel(m.cell_data['component'][0]).tolist()) == {0}
r = json.load(open(os.path.join(d, 'report.json')))
mon = np.genfromtxt(os.path.join(d, 'monitors.csv'), delimiter=',', names=True)
v = mon['volume_jelly_m3']
print('frames', len(sets), 'worst', worst, 'sag', float(-u[:, 2].min()),
      'status', r['status'], 'steps', r['steps'], 'volerr', float(np.abs(v / 8e-6 - 1).max()),
      'time', r['simulated_time_s'], 'rows', len(mon),
      'stepping', r['step_wall_time_s'], 'wall', r['wall_time_s'],
      'stepping_factor', r['stepping_real_time_factor'], 'factor', r['real_time_factor'])
)";

TEST(RunOutput, SeriesMonitorsAndReportReadBack) {
  testing::TempDir dir;
  const auto scene = dir.path() / "jelly.yaml";
  std::ofstream(scene) << kScene;
  const auto out = dir.path() / "out";
  const auto run = run_command(testing::cli() + " run " + scene.string() + " -o " + out.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const auto& e : std::filesystem::directory_iterator(out))
    EXPECT_NE(e.path().extension(), ".tmp") << "left behind: " << e.path();

  const auto script = dir.path() / "read.py";
  std::ofstream(script) << kReader;
  const auto read = run_command("/usr/bin/python3 " + script.string() + " " + out.string());
  ASSERT_EQ(read.exit_code, 0) << "reading the results with meshio failed (make test installs "
                                  "python3-meshio):\n"
                               << read.output;
  std::istringstream in(read.output);
  std::string key, status;
  int frames = 0;
  long steps = 0;
  double worst = 1, sag = 0, volerr = 1, time = 0;
  long rows = 0;
  double stepping = 0, wall = 0, stepping_factor = 0, factor = 0;
  in >> key >> frames >> key >> worst >> key >> sag >> key >> status >> key >> steps >> key >>
      volerr >> key >> time >> key >> rows >> key >> stepping >> key >> wall >> key >>
      stepping_factor >> key >> factor;
  EXPECT_EQ(frames, 5);  // t = 0 and every 0.05 s up to 0.2 s
  EXPECT_LT(worst, 1e-15);
  EXPECT_GT(sag, 1e-4);  // the jelly sags under its weight
  EXPECT_EQ(status, "completed");
  EXPECT_GT(steps, 10);
  EXPECT_LT(volerr, 1e-10);
  EXPECT_NEAR(time, 0.2, 1e-3);
  EXPECT_EQ(rows, steps + 1);  // t = 0, then every step of a run under 1000 steps
  // The steps' own wall time is part of the run's, and their factor is per second of it.
  EXPECT_GT(stepping, 0.0);
  EXPECT_LE(stepping, wall);
  EXPECT_NEAR(stepping_factor * stepping, time, 1e-6 * time);
  EXPECT_GE(stepping_factor, factor);
}

// Reads two runs' series with meshio and prints how many frames hold the same bits in every
// array (points, point and cell data, cells) and the frames' total sizes.
constexpr const char* kCompare = R"(import sys, os, xml.etree.ElementTree as ET
import meshio, numpy as np
a, b = sys.argv[1], sys.argv[2]
def files(d):
    sets = ET.parse(os.path.join(d, 'jelly.pvd')).getroot().find('Collection').findall('DataSet')
    return [os.path.join(d, s.get('file')) for s in sets]
def same(x, y):
    x, y = np.asarray(x), np.asarray(y)
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
fa, fb = files(a), files(b)
equal = 0
for x, y in zip(fa, fb):
    p, q = meshio.read(x), meshio.read(y)
    ok = same(p.points, q.points) and len(p.cells) == len(q.cells)
    ok = ok and all(c.type == d.type and same(c.data, d.data) for c, d in zip(p.cells, q.cells))
    ok = ok and sorted(p.point_data) == sorted(q.point_data) == ['displacement', 'force', 'velocity']
    ok = ok and all(same(p.point_data[k], q.point_data[k]) for k in p.point_data)
    ok = ok and all(same(u, v) for u, v in zip(p.cell_data['component'], q.cell_data['component']))
    equal += ok
print('frames', len(fa), len(fb), 'equal', equal, 'bytes', sum(map(os.path.getsize, fa)),
      sum(map(os.path.getsize, fb)))
)";

// `output.format: binary` writes the same frames as ASCII, bit for bit, in raw appended data.
TEST(RunOutput, BinaryFramesHoldTheAsciiFramesBits) {
  testing::TempDir dir;
  std::ofstream(dir.path() / "jelly.yaml") << kScene;
  std::filesystem::create_directories(dir.path() / "binary");
  std::ofstream(dir.path() / "binary" / "jelly.yaml") << kScene << "  format: binary\n";
  for (const char* scene : {"jelly.yaml", "binary/jelly.yaml"}) {
    const auto out = dir.path() / (std::string(scene) + ".out");
    const auto run = run_command(testing::cli() + " run -q " + (dir.path() / scene).string() +
                                 " -o " + out.string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
  }
  const auto binary_frame = dir.path() / "binary/jelly.yaml.out" / "jelly_000004.vtu";
  EXPECT_NE(testing::read_text(binary_frame).find("<AppendedData encoding=\"raw\">"),
            std::string::npos);
  const auto script = dir.path() / "compare.py";
  std::ofstream(script) << kCompare;
  const auto read = run_command("/usr/bin/python3 " + script.string() + " " +
                                (dir.path() / "jelly.yaml.out").string() + " " +
                                (dir.path() / "binary/jelly.yaml.out").string());
  ASSERT_EQ(read.exit_code, 0) << read.output;
  std::istringstream in(read.output);
  std::string key;
  int ascii_frames = 0, binary_frames = 0, equal = 0;
  long ascii_bytes = 0, binary_bytes = 0;
  in >> key >> ascii_frames >> binary_frames >> key >> equal >> key >> ascii_bytes >> binary_bytes;
  EXPECT_EQ(ascii_frames, 5) << read.output;
  EXPECT_EQ(binary_frames, 5);
  EXPECT_EQ(equal, 5);
  // 8 bytes a double against its shortest text (about 20 characters and a separator).
  EXPECT_LT(binary_bytes, ascii_bytes);
}

// `phymul run --format` decides over the scene's output.format, both ways.
TEST(RunOutput, FormatFlagOverridesTheScene) {
  testing::TempDir dir;
  std::ofstream(dir.path() / "jelly.yaml") << kScene << "  format: binary\n";
  const auto scene = (dir.path() / "jelly.yaml").string();
  for (const char* format : {"ascii", "binary"}) {
    const auto out = dir.path() / format;
    const auto run = run_command(testing::cli() + " run -q " + scene + " --format " + format +
                                 " -o " + out.string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const std::string frame = testing::read_text(out / "jelly_000002.vtu");
    const bool raw = frame.find("<AppendedData encoding=\"raw\">") != std::string::npos;
    const bool text = frame.find("format=\"ascii\"") != std::string::npos;
    EXPECT_EQ(raw, std::string(format) == "binary") << format;
    EXPECT_EQ(text, std::string(format) == "ascii") << format;
  }
  const auto bad = run_command(testing::cli() + " run -q " + scene + " --format xml -o " +
                               (dir.path() / "xml").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--format"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "xml"));
}

TEST(RunOutput, UnknownFormatIsRejectedNamingTheChoices) {
  testing::TempDir dir;
  const auto scene = dir.path() / "jelly.yaml";
  std::ofstream(scene) << kScene << "  format: hdf5\n";
  const auto r = run_command(testing::cli() + " check " + scene.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("format"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("hdf5"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("binary"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("jelly.yaml:15:11:"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A falling bone: monitors.csv has the distance its centre of mass moved, g t^2 / 2.
TEST(RunOutput, MonitorsTrackRigidBodies) {
  testing::TempDir dir;
  const auto scene = dir.path() / "bone.yaml";
  std::ofstream(scene) << R"(simulation: {dt: 1 ms, duration: 0.1 s, gravity: [0, 0, -9.81]}
objects:
  - name: bone
    type: rigid
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [1, 1, 1]}
    material: {density: 1900 kg/m^3}
)";
  const auto out = dir.path() / "out";
  const auto run = testing::run_command(testing::cli() + " run " + scene.string() + " -o " +
                                        out.string() + " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream in(out / "monitors.csv");
  std::string header, line, last;
  std::getline(in, header);
  while (std::getline(in, line)) last = line;
  EXPECT_TRUE(header.ends_with(",volume_bone_m3,displacement_bone_m")) << header;
  const double moved = std::stod(last.substr(last.rfind(',') + 1));
  const double t = std::stod(last.substr(0, last.find(',')));
  EXPECT_NEAR(t, 0.1, 1e-9);
  EXPECT_NEAR(moved, 0.5 * 9.81 * t * t, 1e-9);
}

}  // namespace
}  // namespace phymul

// NIfTI-1 label images: the real prostate segmentation's header as nibabel reads it, the bad
// images of tests/data/bad_images, and every cut of a real file refused, never a crash.
#include "phymul/nifti.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "support/expected_messages.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Nifti, TheProstateSegmentationReadsAsNibabelReadsIt) {
  const LabelImage im =
      read_nifti_labels(testing::source_dir() / "data/prostate_mri/prostate_00.nii.gz");
  EXPECT_EQ(im.dims, (std::array<int, 3>{320, 320, 15}));
  // nibabel 5: img.affine (mm), the sform (sform_code 1); the header stores float32.
  const double affine[3][4] = {{6.00000024e-01, 2.62617619e-12, -1.18562840e-10, -9.81661072e+01},
                               {2.62617445e-12, 5.74392080e-01, 1.15612781e+00, -1.05466675e+02},
                               {1.77844180e-11, -1.73419192e-01, 3.82927990e+00, -3.91753807e+01}};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(im.axes(r, c), affine[r][c] * 1e-3, 1e-11);
    EXPECT_NEAR(im.origin[r], affine[r][3] * 1e-3, 1e-9);
  }
  EXPECT_NEAR(im.spacing()[2], 4.000002e-3, 1e-9);
  const std::map<std::int32_t, size_t> counts{{0, 1503154}, {1, 5813}, {2, 27033}};
  EXPECT_EQ(label_counts(im), counts);
}

// tests/data/bad_images: each with its message in expected.txt ("file | message"), read and
// meshed as `phymul mesh FILE --labels 1 --edge '2 mm'` does.
TEST(Nifti, EveryBadImageReportsItsExpectedMessage) {
  const fs::path dir = testing::source_dir() / "tests/data/bad_images";
  const std::map<std::string, std::string> expected =
      testing::expected_messages(dir / "expected.txt");
  int seen = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (!is_nifti_path(name)) continue;
    ++seen;
    ASSERT_TRUE(expected.contains(name)) << name << " has no line in expected.txt";
    try {
      const LabelImage image = read_nifti_labels(e.path());
      const int labels[] = {1};
      label_surface(image, labels, 2e-3);
      ADD_FAILURE() << name << " was meshed without complaint";
    } catch (const std::runtime_error& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(expected.at(name)), std::string::npos)
          << name << "\n  expected: " << expected.at(name) << "\n  got:      " << what;
    }
  }
  EXPECT_EQ(seen, int(expected.size()));
  EXPECT_GE(seen, 20);
}

TEST(Nifti, EveryCutOfARealFileIsRefusedWithTheFilesName) {
  const std::string gz = read_bytes(testing::source_dir() / "data/prostate_mri/prostate_00.nii.gz");
  for (size_t n = 0; n < gz.size(); n += 97) {
    try {
      parse_nifti_labels(gz.substr(0, n), "cut.nii.gz");
      ADD_FAILURE() << n << " bytes were read";
    } catch (const MeshFileError& e) {
      EXPECT_EQ(e.file, "cut.nii.gz");
    }
  }
}

}  // namespace
}  // namespace phymul

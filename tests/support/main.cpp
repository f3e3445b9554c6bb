// The tests' main: ctest passes the source tree and the program under test as arguments
// (tests/CMakeLists.txt), which become the environment support/process.hpp reads, so that no
// path of the build machine is compiled into the tests (and the programs the tests start
// inherit them).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  for (int i = 1; i < argc; ++i)
    for (const char* name : {"PHYMUL_SOURCE_DIR", "PHYMUL_CLI"}) {
      const size_t n = std::strlen(name);
      if (std::strncmp(argv[i], name, n) == 0 && argv[i][n] == '=')
        setenv(name, argv[i] + n + 1, 1);
    }
  return RUN_ALL_TESTS();
}

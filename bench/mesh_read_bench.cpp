// Reading an organ's surface (issue 23 asks under 1 s for 1 million triangles): a closed torus
// of 1,000,000 triangles as binary STL and as zlib-compressed appended .vtp, each written once
// to a temporary file, then read_mesh_file (read, points merged, surface checked and oriented).
#include <benchmark/benchmark.h>
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "phymul/mesh_io.hpp"

namespace {

using namespace phymul;
namespace fs = std::filesystem;

// A torus (radii 40 and 15 mm) of nu x nv quads, each split in two outward triangles.
struct Surface {
  std::vector<Vec3> points;
  std::vector<Triangle> triangles;
};

Surface torus(int nu, int nv) {
  Surface s;
  constexpr double R = 0.040, r = 0.015, two_pi = 2 * std::numbers::pi;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = two_pi * i / nu, v = two_pi * j / nv;
      s.points.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                          r * std::sin(v)});
    }
  const auto id = [&](int i, int j) { return (i % nu) * nv + j % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

template <class T>
void put(std::string& out, T value) {
  char b[sizeof value];
  std::memcpy(b, &value, sizeof value);
  out.append(b, sizeof value);
}

void write_stl(const fs::path& path, const Surface& s) {
  std::string out(80, ' ');
  put(out, std::uint32_t(s.triangles.size()));
  for (const Triangle& t : s.triangles) {
    for (int k = 0; k < 3; ++k) put(out, 0.0f);  // the normal: readers recompute it
    for (int c : t)
      for (int a = 0; a < 3; ++a) put(out, float(s.points[size_t(c)][a]));
    put(out, std::uint16_t(0));
  }
  std::ofstream(path, std::ios::binary) << out;
}

// One appended array as vtkZLibDataCompressor writes it: UInt64 header, 32 KiB blocks.
std::string zlib_block(const std::string& raw) {
  constexpr size_t kBlock = 32768;
  const size_t blocks = (raw.size() + kBlock - 1) / kBlock;
  std::string header, data;
  put(header, std::uint64_t(blocks));
  put(header, std::uint64_t(kBlock));
  put(header, std::uint64_t(raw.size() % kBlock));
  for (size_t k = 0; k < blocks; ++k) {
    const size_t n = std::min(kBlock, raw.size() - k * kBlock);
    uLongf size = compressBound(uLong(n));
    std::string packed(size, '\0');
    compress(reinterpret_cast<Bytef*>(packed.data()), &size,
             reinterpret_cast<const Bytef*>(raw.data() + k * kBlock), uLong(n));
    put(header, std::uint64_t(size));
    data.append(packed, 0, size);
  }
  return header + data;
}

void write_vtp(const fs::path& path, const Surface& s) {
  std::string points, connectivity, offsets;
  for (const Vec3& p : s.points)
    for (int a = 0; a < 3; ++a) put(points, float(p[a]));
  for (size_t k = 0; k < s.triangles.size(); ++k) {
    for (int c : s.triangles[k]) put(connectivity, std::int64_t(c));
    put(offsets, std::int64_t(3 * (k + 1)));
  }
  const std::string blocks[] = {zlib_block(points), zlib_block(connectivity), zlib_block(offsets)};
  std::ofstream out(path, std::ios::binary);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
         "byte_order=\"LittleEndian\" header_type=\"UInt64\" "
         "compressor=\"vtkZLibDataCompressor\">\n<PolyData>\n<Piece NumberOfPoints=\""
      << s.points.size() << "\" NumberOfPolys=\"" << s.triangles.size()
      << "\">\n<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
         "format=\"appended\" offset=\"0\"/></Points>\n<Polys><DataArray type=\"Int64\" "
         "Name=\"connectivity\" format=\"appended\" offset=\""
      << blocks[0].size()
      << "\"/><DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\""
      << blocks[0].size() + blocks[1].size()
      << "\"/></Polys>\n</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_" << blocks[0]
      << blocks[1] << blocks[2] << "\n</AppendedData>\n</VTKFile>\n";
}

// The surface written once per format, removed at exit.
const fs::path& surface_file(const std::string& extension) {
  static const fs::path dir = [] {
    const fs::path d =
        fs::temp_directory_path() / ("phymul_mesh_bench_" + std::to_string(getpid()));
    fs::create_directories(d);
    const Surface s = torus(1000, 500);  // 1,000,000 triangles
    write_stl(d / "torus.stl", s);
    write_vtp(d / "torus.vtp", s);
    std::atexit([] {
      fs::remove_all(fs::temp_directory_path() / ("phymul_mesh_bench_" + std::to_string(getpid())));
    });
    return d;
  }();
  static const fs::path stl = dir / "torus.stl", vtp = dir / "torus.vtp";
  return extension == ".stl" ? stl : vtp;
}

void read(benchmark::State& state, const std::string& extension) {
  const fs::path& path = surface_file(extension);
  size_t triangles = 0;
  for (auto _ : state) {
    const Mesh mesh = read_mesh_file(path);
    triangles = mesh.cells.size();
    benchmark::DoNotOptimize(mesh.points.data());
  }
  state.counters["triangles"] = double(triangles);
  state.counters["file_MB"] = double(fs::file_size(path)) / 1e6;
}

void BM_ReadBinaryStl(benchmark::State& state) { read(state, ".stl"); }
void BM_ReadZlibVtp(benchmark::State& state) { read(state, ".vtp"); }
BENCHMARK(BM_ReadBinaryStl)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_ReadZlibVtp)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();

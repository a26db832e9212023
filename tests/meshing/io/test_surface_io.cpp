// Surface readers and writers: round trips on procedural meshes, one tiny hand-written file per
// defect class (the error names the line or byte and the defect), MSH with arbitrary node ids and
// physical names, binary MSH written by Gmsh itself, and the real meshes of ../shared/data.
#include <gmsh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/io/msh_parser.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace curvefem::io {
namespace {

namespace fs = std::filesystem;

// This file builds two executables: test_surface_io (label unit) and, with
// CURVEFEM_SURFACE_IO_DATA defined, test_surface_io_data (label data: ../shared/data).
#ifndef CURVEFEM_SURFACE_IO_DATA

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A scratch directory for the running test (created once per test, so tests running in parallel
// processes never share one).
fs::path test_dir() {
  static std::map<std::string, fs::path> dirs;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string name =
      std::string("surface_io_") + info->test_suite_name() + "_" + info->name();
  auto it = dirs.find(name);
  if (it == dirs.end()) it = dirs.emplace(name, test::scratch_dir(name)).first;
  return it->second;
}

// Writes `content` to scratch/name, reads it, expects an InputError whose message contains every
// one of `needles`; returns the message.
std::string expect_input_error(const std::string& name, const std::string& content,
                               std::initializer_list<std::string> needles) {
  const fs::path path = test_dir() / name;
  write_bytes(path, content);
  try {
    read_surface(path);
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const auto& n : needles)
      EXPECT_NE(what.find(n), std::string::npos)
          << "message \"" << what << "\" lacks \"" << n << "\"";
    return what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << name << ": expected InputError, got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << name << ": expected InputError, the file was accepted";
  return {};
}

SurfaceMesh read_text(const std::string& name, const std::string& content) {
  const fs::path path = test_dir() / name;
  write_bytes(path, content);
  return read_surface(path);
}

// Box (tags 1..6 in order of first appearance) with two named tags.
SurfaceMesh tagged_box() {
  SurfaceMesh m = make_box(Eigen::Vector3d(-1, 0, 0.5), Eigen::Vector3d(1, 2.5, 3), 2);
  m.tag_names[1] = "inlet";
  m.tag_names[6] = "outlet wall";
  return m;
}

// Icosphere whose tags are interleaved, not sorted, and include 0 (untagged).
SurfaceMesh interleaved_sphere() {
  SurfaceMesh m = make_icosphere(2, 1.5);
  m.tags.resize(m.F.rows());
  const int values[] = {7, 3, 0, 11};
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) m.tags(f) = values[(f * 7 + f / 5) % 4];
  m.tag_names[3] = "three";
  m.tag_names[11] = "eleven";
  return m;
}

struct FormatCase {
  SurfaceFormat format;
  const char* file;
};
const FormatCase k_formats[] = {
    {SurfaceFormat::obj, "m.obj"},        {SurfaceFormat::off, "m.off"},
    {SurfaceFormat::stl_ascii, "ma.stl"}, {SurfaceFormat::stl_binary, "mb.stl"},
    {SurfaceFormat::ply_ascii, "ma.ply"}, {SurfaceFormat::ply_binary, "mb.ply"},
    {SurfaceFormat::msh22, "m22.msh"},    {SurfaceFormat::msh41, "m41.msh"},
};

bool is_stl(SurfaceFormat f) {
  return f == SurfaceFormat::stl_ascii || f == SurfaceFormat::stl_binary;
}

// STL loses connectivity (rebuilt by welding) and, in binary, double precision: compare the welded
// vertex count and each face's corner positions.
void expect_same_stl_geometry(const SurfaceMesh& original, const SurfaceMesh& read, bool as_float) {
  ASSERT_EQ(read.num_vertices(), original.num_vertices());
  ASSERT_EQ(read.num_faces(), original.num_faces());
  for (Eigen::Index f = 0; f < original.F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        double expected = original.V(original.F(f, c), k);
        if (as_float) expected = static_cast<float>(expected);
        ASSERT_EQ(read.V(read.F(f, c), k), expected) << "face " << f << " corner " << c;
      }
}

// ------------------------------------------------------------------------------------ round trips

TEST(SurfaceIo, RoundTripEveryFormatTaggedBox) {
  const SurfaceMesh m = tagged_box();
  const fs::path dir = test_dir();
  for (const auto& fc : k_formats) {
    SCOPED_TRACE(fc.file);
    write_surface(dir / fc.file, m, fc.format);
    const SurfaceMesh r = read_surface(dir / fc.file);
    if (is_stl(fc.format)) {
      expect_same_stl_geometry(m, r, fc.format == SurfaceFormat::stl_binary);
      EXPECT_EQ(r.tags.size(), 0);
      continue;
    }
    ASSERT_EQ(r.V.rows(), m.V.rows());
    ASSERT_EQ(r.F.rows(), m.F.rows());
    EXPECT_TRUE(r.V == m.V);
    EXPECT_TRUE(r.F == m.F);
    if (fc.format == SurfaceFormat::off) {
      EXPECT_EQ(r.tags.size(), 0);  // OFF has no tags
      continue;
    }
    ASSERT_EQ(r.tags.size(), m.tags.size());
    EXPECT_TRUE(r.tags == m.tags);
    EXPECT_EQ(r.tag_names.at(1), "inlet");
    EXPECT_EQ(r.tag_names.at(6), "outlet wall");
  }
}

TEST(SurfaceIo, RoundTripInterleavedTagsKeepsFaceOrderAndValues) {
  // Tag values survive exactly in PLY and MSH (in MSH 4.1 the faces are grouped by entity on
  // write; element ids restore the order). OBJ renumbers groups by first appearance.
  const SurfaceMesh m = interleaved_sphere();
  const fs::path dir = test_dir();
  for (const auto& fc : k_formats) {
    SCOPED_TRACE(fc.file);
    write_surface(dir / fc.file, m, fc.format);
    const SurfaceMesh r = read_surface(dir / fc.file);
    if (is_stl(fc.format)) {
      expect_same_stl_geometry(m, r, fc.format == SurfaceFormat::stl_binary);
      continue;
    }
    ASSERT_EQ(r.F.rows(), m.F.rows());
    EXPECT_TRUE(r.V == m.V);
    EXPECT_TRUE(r.F == m.F);
    if (fc.format == SurfaceFormat::off) continue;
    ASSERT_EQ(r.tags.size(), m.tags.size());
    if (fc.format == SurfaceFormat::obj) {
      // Same partition: equal original tags <=> equal read tags; 0 stays 0.
      std::map<int, int> map;
      for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
        auto [it, inserted] = map.try_emplace(m.tags(f), r.tags(f));
        EXPECT_EQ(it->second, r.tags(f));
        EXPECT_EQ(m.tags(f) == 0, r.tags(f) == 0);
      }
      EXPECT_EQ(map.size(), 4u);
      EXPECT_EQ(r.tag_names.at(map[3]), "three");
      continue;
    }
    EXPECT_TRUE(r.tags == m.tags);
    EXPECT_EQ(r.tag_names.at(11), "eleven");
  }
}

TEST(SurfaceIo, RoundTripUntaggedTorusHasNoTags) {
  const SurfaceMesh m = make_torus(2.0, 0.5, 12, 8);
  const fs::path dir = test_dir();
  for (const auto& fc : k_formats) {
    SCOPED_TRACE(fc.file);
    write_surface(dir / fc.file, m, fc.format);
    const SurfaceMesh r = read_surface(dir / fc.file);
    EXPECT_EQ(r.num_faces(), m.num_faces());
    EXPECT_EQ(r.num_vertices(), m.num_vertices());
    EXPECT_EQ(r.tags.size(), 0);
  }
}

TEST(SurfaceIo, FormatFromExtension) {
  EXPECT_EQ(surface_format_from_extension("a/b.OBJ"), SurfaceFormat::obj);
  EXPECT_EQ(surface_format_from_extension("x.off"), SurfaceFormat::off);
  EXPECT_EQ(surface_format_from_extension("x.stl"), SurfaceFormat::stl_binary);
  EXPECT_EQ(surface_format_from_extension("x.Ply"), SurfaceFormat::ply_binary);
  EXPECT_EQ(surface_format_from_extension("x.msh"), SurfaceFormat::msh41);
  EXPECT_THROW(surface_format_from_extension("x.vtk"), InputError);
  expect_input_error("mesh.xyz", "v 0 0 0\n", {"unknown surface format", ".xyz"});
}

TEST(SurfaceIo, MissingFileIsIoError) {
  EXPECT_THROW(read_surface(test_dir() / "none.obj"), IoError);
}

// ------------------------------------------------------------------------------------------ OBJ

TEST(SurfaceIoObj, NegativeIndicesAndSlashTokens) {
  const SurfaceMesh m = read_text("neg.obj",
                                  "# comment\nmtllib x.mtl\no thing\ns off\n"
                                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
                                  "f -3 -1 -2\n"
                                  "v 0 0 1\n"
                                  "f 1/1 2/1/1 -1//1\n"
                                  "f -4/1/1 -1 3\n"
                                  "f   2  3   4  \r\n");
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 4);
  Eigen::MatrixXi expected(4, 3);
  expected << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  EXPECT_TRUE(m.F == expected);
  EXPECT_EQ(m.tags.size(), 0);
}

TEST(SurfaceIoObj, InlineCommentsAndUnderflow) {
  const SurfaceMesh m = read_text("c.obj",
                                  "v 0 0 0 # origin\nv 1 0 1e-400\nv +0 1 4.9e-324\n"
                                  "g top # the lid\nf 1 2 3 # one face\n");
  ASSERT_EQ(m.num_faces(), 1);
  EXPECT_EQ(m.V(1, 2), 0.0);
  EXPECT_GT(m.V(2, 2), 0.0);
  EXPECT_EQ(m.tag_names.at(1), "top");
}

TEST(SurfaceIoObj, GroupsAndMaterialsBecomeTags) {
  const SurfaceMesh g =
      read_text("groups.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                "f 1 3 2\ng lid\nf 1 2 4\ng side wall\nf 1 4 3\ng lid\nf 2 3 4\n");
  ASSERT_EQ(g.tags.size(), 4);
  EXPECT_EQ(g.tags(0), 0);
  EXPECT_EQ(g.tags(1), 1);
  EXPECT_EQ(g.tags(2), 2);
  EXPECT_EQ(g.tags(3), 1);
  EXPECT_EQ(g.tag_names.at(1), "lid");
  EXPECT_EQ(g.tag_names.at(2), "side wall");
  const SurfaceMesh u = read_text("mtl.obj",
                                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                  "usemtl red\nf 1 3 2\nf 1 2 4\nusemtl blue\nf 1 4 3\nf 2 3 4\n");
  ASSERT_EQ(u.tags.size(), 4);
  EXPECT_EQ(u.tags(0), 1);
  EXPECT_EQ(u.tags(2), 2);
  EXPECT_EQ(u.tag_names.at(2), "blue");
}

TEST(SurfaceIoObj, Defects) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
  expect_input_error("quad.obj", v + "f 1 2 3\nf 1 2 3 4\n",
                     {"quad.obj:6:", "face has 4 vertices", "triangles"});
  expect_input_error("quad2.obj", v + "f 1 2 3\nf 1 2 3 4\n", {"split polygons"});
  expect_input_error("line.obj", v + "f 1 2\n", {":5:", "face has 2 vertices"});
  expect_input_error("range.obj", v + "f 1 2 3\nf 1 2 9\n",
                     {"range.obj:6:", "vertex index 9 out of range", "4 vertices"});
  expect_input_error("zero.obj", v + "f 0 1 2\n", {":5:", "index 0"});
  expect_input_error("rel.obj", v + "f -5 1 2\n", {":5:", "relative vertex index -5"});
  expect_input_error("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
                     {"nan.obj:2:", "vertex y", "NaN/inf"});
  expect_input_error("inf.obj", "v 0 0 0\nv 1 0 -inf\nv 0 1 0\nf 1 2 3\n", {":2:", "NaN/inf"});
  expect_input_error("huge.obj", "v 0 0 1e999\n", {":1:", "expected a number"});
  expect_input_error("short.obj", "v 0 0\nf 1 1 1\n", {":1:", "missing vertex z"});
  expect_input_error("token.obj", v + "f 1 2 x3\n", {":5:", "bad face vertex \"x3\""});
  expect_input_error("unknown.obj", v + "vx 1 2 3\n", {":5:", "unknown OBJ statement \"vx\""});
  expect_input_error("curve.obj", v + "curv 0 1 1 2\n", {":5:", "free-form"});
  expect_input_error("empty.obj", "", {"empty.obj", "empty file"});
  expect_input_error("blank.obj", "\n  \n\t\n", {"empty file"});
  expect_input_error("nofaces.obj", v, {"no triangles"});
}

// ------------------------------------------------------------------------------------------ OFF

TEST(SurfaceIoOff, CommentsColoursAndCountsOnHeaderLine) {
  const SurfaceMesh a = read_text("c.off",
                                  "# leading comment\n\nOFF\n# counts\n4 4 6\n"
                                  "0 0 0\n1 0 0 # x axis\n0 1 0\n0 0 1\n"
                                  "3 0 2 1\n3 0 1 3 255 0 0\n\n3 0 3 2\n3 1 2 3\n");
  EXPECT_EQ(a.num_vertices(), 4);
  EXPECT_EQ(a.num_faces(), 4);
  EXPECT_EQ(a.F(1, 2), 3);
  const SurfaceMesh b = read_text("h.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const SurfaceMesh c =
      read_text("k.off", "OFF # header\n3 1 0 # counts\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n# end\n");
  EXPECT_EQ(c.num_faces(), 1);
  EXPECT_EQ(b.num_faces(), 1);
}

TEST(SurfaceIoOff, Defects) {
  const std::string h = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  expect_input_error("quad.off", h + "3 0 1 2\n4 0 1 2 3\n",
                     {"quad.off:8:", "face has 4 vertices", "split polygons"});
  expect_input_error("range.off", h + "3 0 1 2\n3 0 1 4\n",
                     {":8:", "vertex index 4 out of range", "4 vertices"});
  expect_input_error("neg.off", h + "3 0 -1 2\n3 0 1 2\n", {":7:", "negative vertex index -1"});
  expect_input_error("trunc.off", h + "3 0 1 2\n",
                     {"trunc.off:7:", "truncated", "2 faces, found 1"});
  expect_input_error("truncv.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n", {"truncated"});
  expect_input_error("absurd.off", "OFF\n4 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                     {"absurd.off:2:", "1000000000000"});
  expect_input_error("absurdv.off", "OFF\n99999999 1 0\n0 0 0\n", {":2:", "99999999 vertices"});
  expect_input_error("negcount.off", "OFF\n-3 1 0\n", {":2:", "negative"});
  expect_input_error("more.off", h + "3 0 1 2\n3 0 1 3\n3 1 2 3\n", {":9:", "count mismatch"});
  expect_input_error("nan.off", "OFF\n3 1 0\n0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n", {":4:", "NaN/inf"});
  expect_input_error("noheader.off", "3 1 0\n0 0 0\n", {":1:", "missing OFF header"});
  expect_input_error("4d.off", "4OFF\n", {":1:", "unsupported OFF variant"});
  expect_input_error("bin.off", "OFF BINARY\n", {":1:", "binary OFF"});
  expect_input_error("empty.off", "", {"empty file"});
  expect_input_error("badcount.off", "OFF\n3 x 0\n", {":2:", "face count"});
}

// ------------------------------------------------------------------------------------------ STL

std::string stl_binary_bytes(const std::string& header, std::uint32_t announced,
                             const std::vector<std::array<float, 9>>& tris) {
  std::string out = header;
  out.resize(80, ' ');
  out.append(reinterpret_cast<const char*>(&announced), 4);
  for (const auto& t : tris) {
    const float normal[3] = {0, 0, 1};
    out.append(reinterpret_cast<const char*>(normal), 12);
    out.append(reinterpret_cast<const char*>(t.data()), 36);
    out.append(2, '\0');
  }
  return out;
}

TEST(SurfaceIoStl, BinaryStartingWithSolidIsBinaryAndWelds) {
  std::vector<std::array<float, 9>> tris = {{0, 0, 0, 1, 0, 0, 0, 1, 0},
                                            {1, 0, 0, 1, 1, 0, 0, 1, 0}};
  const SurfaceMesh m = read_text("solid.stl", stl_binary_bytes("solid exported", 2, tris));
  EXPECT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.F(1, 0), 1);
  EXPECT_EQ(m.F(1, 2), 2);
}

TEST(SurfaceIoStl, AsciiMultipleSolidsUppercase) {
  const SurfaceMesh m = read_text("two.stl",
                                  "SOLID a\nFACET NORMAL 0 0 1\nOUTER LOOP\nVERTEX 0 0 0\n"
                                  "VERTEX 1 0 0\nVERTEX 0 1 0\nENDLOOP\nENDFACET\nENDSOLID a\n"
                                  "solid b\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\n"
                                  "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid b\n");
  EXPECT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.num_vertices(), 4);
}

TEST(SurfaceIoStl, Defects) {
  const std::string facet =
      "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n"
      " endloop\nendfacet\n";
  expect_input_error("quad.stl",
                     "solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                     "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid q\n",
                     {"quad.stl:7:", "more than 3 vertices", "triangles"});
  expect_input_error("trunc.stl", "solid t\n" + facet + "facet normal 0 0 1\n outer loop\n",
                     {"trunc.stl:10:", "truncated"});
  expect_input_error("noend.stl", "solid t\n" + facet, {"missing \"endsolid\""});
  expect_input_error("nan.stl",
                     "solid n\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\n"
                     "vertex 0 1 0\nendloop\nendfacet\nendsolid\n",
                     {":5:", "vertex y is NaN/inf"});
  expect_input_error("word.stl", "solid w\nfacet normal 0 0 1\nouter lop\n",
                     {":3:", "expected \"loop\""});
  std::vector<std::array<float, 9>> one = {{0, 0, 0, 1, 0, 0, 0, 1, 0}};
  // Header announces 10^9 triangles in a 134-byte file.
  expect_input_error("absurd.stl", stl_binary_bytes("bin", 1000000000u, one),
                     {"absurd.stl: byte 80:", "1000000000 triangles", "134 bytes"});
  std::string cut = stl_binary_bytes("bin", 2, {one[0], one[0]});
  cut.resize(cut.size() - 7);
  expect_input_error("cut.stl", cut, {"byte 80", "2 triangles", "177 bytes"});
  auto nan_tris = one;
  nan_tris[0][4] = std::numeric_limits<float>::quiet_NaN();
  expect_input_error("nanbin.stl", stl_binary_bytes("bin", 1, nan_tris),
                     {"byte 112", "NaN/inf", "face 0"});
  std::string solid_cut = stl_binary_bytes("solid but binary", 2, {one[0], one[0]});
  solid_cut.resize(solid_cut.size() - 1);
  expect_input_error("solidcut.stl", solid_cut, {"binary STL", "2 triangles"});
  expect_input_error("tiny.stl", "abc", {"not an STL"});
  expect_input_error("empty.stl", "", {"empty file"});
}

// ------------------------------------------------------------------------------------------ PLY

template <class T>
void put_be(std::string& out, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (std::endian::native == std::endian::little) std::reverse(b, b + sizeof(T));
  out.append(b, sizeof(T));
}

TEST(SurfaceIoPly, BigEndianMixedTypesAndLabelTag) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\ncomment hand made\nobj_info x\n"
      "element vertex 4\nproperty float x\nproperty short y\nproperty double z\n"
      "property uchar red\n"
      "element face 2\nproperty int flags\nproperty list ushort uint vertex_index\n"
      "property char label\nelement edge 1\nproperty list uchar int vertex_indices\n"
      "end_header\n";
  const float xs[4] = {0, 1, 0, 0};
  const std::int16_t ys[4] = {0, 0, 1, 0};
  const double zs[4] = {0, 0, 0, 1};
  for (int v = 0; v < 4; ++v) {
    put_be(s, xs[v]);
    put_be(s, ys[v]);
    put_be(s, zs[v]);
    put_be(s, std::uint8_t{200});
  }
  const std::uint32_t faces[2][3] = {{0, 2, 1}, {0, 1, 3}};
  for (int f = 0; f < 2; ++f) {
    put_be(s, std::int32_t{99});
    put_be(s, std::uint16_t{3});
    for (auto i : faces[f]) put_be(s, i);
    put_be(s, static_cast<std::int8_t>(f == 0 ? -2 : 5));
  }
  put_be(s, std::uint8_t{2});
  put_be(s, std::int32_t{0});
  put_be(s, std::int32_t{1});
  const SurfaceMesh m = read_text("be.ply", s);
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 2);
  EXPECT_EQ(m.V(1, 0), 1.0);
  EXPECT_EQ(m.V(2, 1), 1.0);
  EXPECT_EQ(m.V(3, 2), 1.0);
  EXPECT_EQ(m.F(0, 1), 2);
  EXPECT_EQ(m.F(1, 2), 3);
  ASSERT_EQ(m.tags.size(), 2);  // "label" preferred over the first int property "flags"
  EXPECT_EQ(m.tags(0), -2);
  EXPECT_EQ(m.tags(1), 5);
}

TEST(SurfaceIoPly, AsciiFirstIntFacePropertyIsTagAndUnusedValuesAreSkipped) {
  const SurfaceMesh m = read_text(
      "a.ply",
      "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty double x\r\nproperty double y\r\n"
      "property double z\r\nproperty float nx\r\nelement face 1\r\nproperty float quality\r\n"
      "property list uchar int vertex_indices\r\nproperty uint patch\r\nend_header\r\n"
      "0 0 0 nan\r\n1 0 0 0\r\n0 1 0 0\r\n0.5 3 0 1 2 42\r\n");  // unused nx may be NaN
  ASSERT_EQ(m.tags.size(), 1);
  EXPECT_EQ(m.tags(0), 42);
}

TEST(SurfaceIoPly, Defects) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string verts = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  expect_input_error("quad.ply", head + verts + "3 0 1 2\n4 0 1 2 3\n",
                     {"quad.ply:15:", "4 vertices", "split polygons"});
  expect_input_error("range.ply", head + verts + "3 0 1 2\n3 0 1 7\n",
                     {":15:", "vertex index 7 out of range"});
  expect_input_error("neg.ply", head + verts + "3 0 -1 2\n3 0 1 2\n",
                     {":14:", "negative vertex index"});
  expect_input_error("trunc.ply", head + verts + "3 0 1 2\n", {"trunc.ply:14:", "truncated"});
  expect_input_error("more.ply", head + verts + "3 0 1 2\n3 0 1 3\n3 0 1 3\n",
                     {":16:", "count mismatch"});
  expect_input_error("nan.ply", head + "0 0 0\n1 inf 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n",
                     {":11:", "NaN/inf"});
  expect_input_error("noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n",
                     {"missing \"end_header\""});
  expect_input_error("magic.ply", "plx\n", {":1:", "not a PLY"});
  expect_input_error("nox.ply",
                     "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nelement face 0\n"
                     "property list uchar int vertex_indices\nend_header\n",
                     {"lacks one of the properties x, y, z"});
  expect_input_error("absurd.ply",
                     "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
                     "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n\x01\x02",
                     {"absurd.ply:3:", "1000000000000"});
  std::string bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  const std::size_t data_start = bin.size();
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bin.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  bin.push_back(3);
  const std::int32_t idx[3] = {0, 1, 5};
  bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
  expect_input_error("binrange.ply", bin,
                     {"byte " + std::to_string(data_start + 36 + 1 + 8), "index 5 out of range"});
  expect_input_error("bincut.ply", bin.substr(0, bin.size() - 3), {"truncated", "byte"});
  expect_input_error("empty.ply", "", {"empty file"});
}

// ------------------------------------------------------------------------------------------ MSH

TEST(SurfaceIoMsh, Msh22NonContiguousIdsPhysicalNamesAndOtherElements) {
  const SurfaceMesh m = read_text(
      "ids22.msh",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
      "$Comments\nanything $Nodes here\n$EndComments\n"
      "$PhysicalNames\n3\n2 5 \"skin\"\n2 9 \"lid top\"\n3 5 \"volume five\"\n$EndPhysicalNames\n"
      "$Nodes\n4\n100 0 0 0\n7 1 0 0\n55 0 1 0\n3 0 0 1\n$EndNodes\n"
      "$Elements\n6\n"
      "1 15 2 0 1 100\n"
      "2 1 2 0 1 100 7\n"
      "10 2 2 5 1 100 55 7\n"
      "11 2 2 5 1 100 7 3\n"
      "4 2 2 9 2 100 3 55\n"
      "12 4 2 5 1 100 7 55 3\n"
      "$EndElements\n"
      "$NodeData\n1\n\"u\"\n$EndNodeData\n");
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 3);
  // Faces ordered by element id: 4, 10, 11; node order of the file: 100, 7, 55, 3.
  Eigen::MatrixXi expected(3, 3);
  expected << 0, 3, 2, 0, 2, 1, 0, 1, 3;
  EXPECT_TRUE(m.F == expected) << m.F;
  ASSERT_EQ(m.tags.size(), 3);
  EXPECT_EQ(m.tags(0), 9);
  EXPECT_EQ(m.tags(1), 5);
  EXPECT_EQ(m.tag_names.at(5), "skin");  // the dimension-2 name, not the volume's
  EXPECT_EQ(m.tag_names.at(9), "lid top");
  EXPECT_EQ(m.V(1, 0), 1.0);
  const auto data = detail::parse_msh(test_dir() / "ids22.msh");
  EXPECT_EQ(data.physical_names_by_dim.at({3, 5}), "volume five");
  EXPECT_EQ(data.blocks.size(), 5u);  // point, line, tri (entity 1), tri (entity 2), tet
}

TEST(SurfaceIoMsh, Msh41NonContiguousIdsEntitiesAndPhysicalNames) {
  const SurfaceMesh m = read_text("ids41.msh",
                                  "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                  "$PhysicalNames\n1\n2 4 \"wall\"\n$EndPhysicalNames\n"
                                  "$Entities\n1 0 2 0\n"
                                  "1 0 0 0 0\n"
                                  "3 0 0 0 1 1 1 1 4 2 1 -2\n"
                                  "8 0 0 0 1 1 1 0 0\n"
                                  "$EndEntities\n"
                                  "$Nodes\n2 4 3 900\n"
                                  "2 3 0 3\n900\n3\n17\n0 0 0\n1 0 0\n0 1 0\n"
                                  "2 8 1 1\n40\n0 0 1 0.25 0.75\n"
                                  "$EndNodes\n"
                                  "$Elements\n2 3 5 30\n"
                                  "2 3 2 2\n30 900 17 3\n5 900 3 40\n"
                                  "2 8 2 1\n6 3 17 40\n"
                                  "$EndElements\n");
  ASSERT_EQ(m.num_vertices(), 4);
  ASSERT_EQ(m.num_faces(), 3);
  Eigen::MatrixXi expected(3, 3);  // element ids 5, 6, 30
  expected << 0, 1, 3, 1, 2, 3, 0, 2, 1;
  EXPECT_TRUE(m.F == expected) << m.F;
  ASSERT_EQ(m.tags.size(), 3);
  EXPECT_EQ(m.tags(0), 4);
  EXPECT_EQ(m.tags(1), 0);
  EXPECT_EQ(m.tag_names.at(4), "wall");
}

TEST(SurfaceIoMsh, Defects) {
  const std::string fmt22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  const std::string nodes22 = "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n";
  expect_input_error("missing.msh",
                     fmt22 + nodes22 + "$Elements\n1\n1 2 2 1 1 1 2 4\n$EndElements\n",
                     {"missing.msh:12:", "references node 4"});
  expect_input_error("absurd.msh", fmt22 + "$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n",
                     {"absurd.msh:5:", "1000000000000"});
  expect_input_error("fewer.msh", fmt22 + "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n",
                     {":9:", "count mismatch"});
  expect_input_error("more.msh", fmt22 + "$Nodes\n2\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n",
                     {":8:", "expected \"$EndNodes\""});
  expect_input_error("dup.msh", fmt22 + "$Nodes\n2\n1 0 0 0\n1 1 0 0\n$EndNodes\n",
                     {":7:", "duplicate node id 1"});
  expect_input_error("nan.msh", fmt22 + "$Nodes\n1\n1 0 nan 0\n$EndNodes\n", {":6:", "NaN/inf"});
  expect_input_error("type.msh", fmt22 + nodes22 + "$Elements\n1\n1 77 0 1 2 3\n$EndElements\n",
                     {"type.msh:12:", "element type 77"});
  expect_input_error("trunc.msh", fmt22 + nodes22 + "$Elements\n1\n1 2 2 1 1 1 2", {"truncated"});
  expect_input_error("noend.msh", fmt22 + "$Nodes\n1\n1 0 0 0\n", {"missing \"$EndNodes\""});
  expect_input_error("v40.msh", "$MeshFormat\n4 0 8\n$EndMeshFormat\n", {":2:", "version 4"});
  expect_input_error("notmsh.msh", "hello\n", {":1:", "not a Gmsh MSH file"});
  expect_input_error("v1.msh", "$NOD\n1\n1 0 0 0\n$ENDNOD\n", {":1:", "MSH 1.0"});
  expect_input_error("notri.msh", fmt22 + nodes22 + "$Elements\n1\n1 1 2 1 1 1 2\n$EndElements\n",
                     {"no 3-node triangles", "types present: 1"});
  expect_input_error("empty.msh", "", {"empty file"});
  expect_input_error("noelem.msh", fmt22 + nodes22, {"no $Elements"});
  expect_input_error("skip.msh", fmt22 + "$Foo\n1 2 3\n", {"$Foo has no \"$EndFoo\""});
  const std::string fmt41 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  expect_input_error("absurd41.msh", fmt41 + "$Nodes\n1 99999999999 1 1\n2 1 0 1\n1\n0 0 0\n",
                     {"absurd41.msh:5:", "99999999999"});
  expect_input_error("block41.msh", fmt41 + "$Nodes\n1 1 1 1\n2 1 0 5\n1\n0 0 0\n",
                     {":6:", "more nodes than the 1 announced"});
  expect_input_error("dim41.msh",
                     fmt41 + "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n" +
                         "$Elements\n1 1 1 1\n3 1 2 1\n1 1 2 3\n$EndElements\n",
                     {"dim41.msh:16:", "dimension 3 holds element type 2"});
}

// Binary MSH written by Gmsh itself (2.2 and 4.1) from our ascii 4.1 output reads back equal.
TEST(SurfaceIoMsh, BinaryFilesWrittenByGmsh) {
  const SurfaceMesh m = tagged_box();
  const fs::path dir = test_dir();
  write_surface(dir / "ascii41.msh", m, SurfaceFormat::msh41);
  for (double version : {2.2, 4.1}) {
    SCOPED_TRACE(version);
    const fs::path out = dir / (version == 2.2 ? "bin22.msh" : "bin41.msh");
    {
      GmshSession session;
      gmsh::open((dir / "ascii41.msh").string());
      gmsh::option::setNumber("Mesh.Binary", 1);
      gmsh::option::setNumber("Mesh.MshFileVersion", version);
      gmsh::write(out.string());
      gmsh::option::setNumber("Mesh.Binary", 0);
    }
    const auto data = detail::parse_msh(out);
    EXPECT_TRUE(data.binary);
    const SurfaceMesh r = read_surface(out);
    ASSERT_EQ(r.num_faces(), m.num_faces());
    ASSERT_EQ(r.num_vertices(), m.num_vertices());
    ASSERT_EQ(r.tags.size(), m.tags.size());
    for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
      EXPECT_EQ(r.tags(f), m.tags(f));
      for (int c = 0; c < 3; ++c)
        EXPECT_TRUE(r.V.row(r.F(f, c)) == m.V.row(m.F(f, c))) << "face " << f;
    }
    EXPECT_EQ(r.tag_names.at(6), "outlet wall");
    // Truncating the binary file anywhere in the node data is an error naming a byte offset.
    std::string bytes = read_bytes(out);
    const std::size_t at = bytes.find("$Nodes") + 40;
    write_bytes(dir / "cut.msh", bytes.substr(0, at));
    try {
      read_surface(dir / "cut.msh");
      ADD_FAILURE() << "truncated binary MSH accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("byte"), std::string::npos) << e.what();
    }
  }
}

// The element type table agrees with Gmsh's own.
TEST(SurfaceIoMsh, ElementTypeTableMatchesGmsh) {
  GmshSession session;
  int checked = 0;
  for (int type = 1; type <= 93; ++type) {
    const int nodes = detail::gmsh_nodes_per_element(type);
    if (nodes < 0) continue;
    // Gmsh 4.8's prism basis mixes new[] and delete (AddressSanitizer aborts): table values only.
    if (type == 6 || type == 13 || type == 18) {
      EXPECT_EQ(nodes, type == 6 ? 6 : type == 13 ? 18 : 15);
      EXPECT_EQ(detail::gmsh_element_dim(type), 3);
      continue;
    }
    std::string name;
    int dim = 0, order = 0, num_nodes = 0, num_primary = 0;
    std::vector<double> local;
    gmsh::model::mesh::getElementProperties(type, name, dim, order, num_nodes, local, num_primary);
    EXPECT_EQ(nodes, num_nodes) << "type " << type << " " << name;
    EXPECT_EQ(detail::gmsh_element_dim(type), dim) << "type " << type << " " << name;
    ++checked;
  }
  EXPECT_GE(checked, 30);
}

#else  // CURVEFEM_SURFACE_IO_DATA

// ------------------------------------------------------------------------------ shared data set

// Column index of `name` in a TSV header line, or -1.
int column_of(const std::string& header, const std::string& name) {
  std::istringstream s(header);
  std::string cell;
  for (int i = 0; std::getline(s, cell, '\t'); ++i)
    if (cell == name) return i;
  return -1;
}

TEST(SurfaceIoData, DevMeshesMatchManifestCounts) {
  const auto data = test::shared_data_dir();
  if (!data) GTEST_SKIP() << test::k_no_data_message;
  std::ifstream manifest(*data / "dev" / "MANIFEST.tsv");
  ASSERT_TRUE(manifest) << "dev/MANIFEST.tsv missing";
  std::string header;
  std::getline(manifest, header);
  const int col_file = column_of(header, "file"), col_v = column_of(header, "V"),
            col_f = column_of(header, "F");
  ASSERT_GE(col_file, 0);
  ASSERT_GE(col_v, 0);
  ASSERT_GE(col_f, 0);
  int read = 0;
  for (std::string row; std::getline(manifest, row);) {
    if (row.empty()) continue;
    std::vector<std::string> cells;
    std::istringstream s(row);
    for (std::string cell; std::getline(s, cell, '\t');) cells.push_back(cell);
    ASSERT_GT(cells.size(), static_cast<std::size_t>(std::max({col_file, col_v, col_f})));
    SCOPED_TRACE(cells[static_cast<std::size_t>(col_file)]);
    const SurfaceMesh m = read_surface(*data / "dev" / cells[static_cast<std::size_t>(col_file)]);
    EXPECT_EQ(m.num_vertices(), std::stoi(cells[static_cast<std::size_t>(col_v)]));
    EXPECT_EQ(m.num_faces(), std::stoi(cells[static_cast<std::size_t>(col_f)]));
    ++read;
  }
  EXPECT_EQ(read, 19);
}

TEST(SurfaceIoData, QuadTorusIsRejected) {
  const auto data = test::shared_data_dir();
  if (!data) GTEST_SKIP() << test::k_no_data_message;
  try {
    read_surface(*data / "bad" / "quads_torus.off");
    FAIL() << "quads_torus.off accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("quads_torus.off:"), std::string::npos) << what;
    EXPECT_NE(what.find("4 vertices"), std::string::npos) << what;
    EXPECT_NE(what.find("polygons"), std::string::npos) << what;
  }
}

#endif  // CURVEFEM_SURFACE_IO_DATA

}  // namespace
}  // namespace curvefem::io

// SPDX-License-Identifier: BSD-3-Clause
#include "ext/render/model_export.h"

#include "ext/core/errors.h"
#include "ext/core/file_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace fs = std::filesystem;

namespace bayon {
namespace {

// A unit cube whose six sides are six charts of a 3 x 2 atlas: 8 vertices,
// 12 triangles, and at every vertex three different texture coordinates.
// The atlas is noise, so that any resampling or colour change shows.
TexturedModel CubeModel() {
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  for (int i = 0; i < 8; ++i) {
    // Offsets that are no round numbers in binary or decimal.
    mesh.vertices.positions.emplace_back(10.1 + (i & 1) * 1.3,
                                         -4.7 + ((i >> 1) & 1) * 1.3,
                                         2.9 + (i >> 2) * 1.3);
  }
  // Each side: four corners counter-clockwise seen from outside.
  const int sides[6][4] = {{0, 2, 3, 1},
                           {4, 5, 7, 6},
                           {0, 1, 5, 4},
                           {2, 6, 7, 3},
                           {0, 4, 6, 2},
                           {1, 3, 7, 5}};
  for (int s = 0; s < 6; ++s) {
    const float u0 = (s % 3) / 3.0f + 0.01f, v0 = (s / 3) / 2.0f + 0.01f;
    const float du = 1 / 3.0f - 0.02f, dv = 0.5f - 0.02f;
    const Eigen::Vector2f uv[4] = {
        {u0, v0}, {u0 + du, v0}, {u0 + du, v0 + dv}, {u0, v0 + dv}};
    const int* c = sides[s];
    mesh.faces.emplace_back(c[0], c[1], c[2]);
    mesh.face_texcoords.push_back({uv[0], uv[1], uv[2]});
    mesh.faces.emplace_back(c[0], c[2], c[3]);
    mesh.face_texcoords.push_back({uv[0], uv[2], uv[3]});
  }
  model.atlas.create(64, 96, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(model.atlas, cv::RNG::UNIFORM, 0, 256);
  return model;
}

// A 3 x 3 grid with one chart: texture coordinates agree wherever faces
// share a vertex, so no vertex needs to be split.
TexturedModel GridModel() {
  TexturedModel model;
  TriangleMesh& mesh = model.mesh;
  const int n = 3;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh.vertices.positions.emplace_back(i * 0.5, j * 0.5, 0.1 * i * j);
    }
  }
  auto uv = [&](int v) {
    return Eigen::Vector2f(float(v % (n + 1)) / n, float(v / (n + 1)) / n);
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.faces.emplace_back(a, b, d);
      mesh.face_texcoords.push_back({uv(a), uv(b), uv(d)});
      mesh.faces.emplace_back(a, d, c);
      mesh.face_texcoords.push_back({uv(a), uv(d), uv(c)});
    }
  }
  model.atlas = cv::Mat(32, 32, CV_8UC3, cv::Scalar(30, 140, 220));
  return model;
}

// Same faces, corner by corner: positions and texture coordinates within
// `tolerance`, the atlas identical pixel for pixel.
void ExpectSameModel(const TexturedModel& expected,
                     const TexturedModel& actual,
                     double tolerance) {
  ASSERT_EQ(actual.mesh.NumFaces(), expected.mesh.NumFaces());
  ASSERT_TRUE(actual.mesh.HasTexcoords());
  for (size_t f = 0; f < expected.mesh.NumFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p =
          expected.mesh.vertices.positions[expected.mesh.faces[f][k]];
      const Eigen::Vector3d& q =
          actual.mesh.vertices.positions[actual.mesh.faces[f][k]];
      EXPECT_LE((p - q).norm(), tolerance * (p.norm() + 1.0)) << "face " << f;
      EXPECT_LE((expected.mesh.face_texcoords[f][k] -
                 actual.mesh.face_texcoords[f][k])
                    .norm(),
                1e-6)
          << "face " << f << " corner " << k;
    }
  }
  ASSERT_EQ(actual.atlas.type(), CV_8UC3);
  ASSERT_EQ(actual.atlas.size(), expected.atlas.size());
  EXPECT_EQ(cv::norm(actual.atlas, expected.atlas, cv::NORM_INF), 0.0);
}

uint32_t U32(const std::string& bytes, size_t offset) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + offset, 4);
  return value;
}

TEST(ModelExport, WritesEveryFormat) {
  const std::string dir = testing::TempDir("model_export_all");
  const std::vector<std::string> written =
      WriteTexturedModel(CubeModel(), dir + "/model", ModelExportOptions());
  const std::vector<std::string> expected = {"model.png",
                                             "model.obj",
                                             "model.mtl",
                                             "model.ply",
                                             "model.wrl",
                                             "model.glb"};
  ASSERT_EQ(written.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(fs::path(written[i]).filename().string(), expected[i]);
    EXPECT_TRUE(fs::is_regular_file(written[i])) << written[i];
  }
  // No temporary files left behind.
  EXPECT_EQ(ListFilesRecursive(dir + "/model").size(), expected.size());
  EXPECT_NE(ReadFileToString(dir + "/model/model.ply")
                .find("comment TextureFile model.png\n"),
            std::string::npos);
  EXPECT_NE(
      ReadFileToString(dir + "/model/model.mtl").find("map_Kd model.png\n"),
      std::string::npos);
  const std::string wrl = ReadFileToString(dir + "/model/model.wrl");
  EXPECT_EQ(wrl.rfind("#VRML V2.0 utf8\n", 0), 0u);
  EXPECT_NE(wrl.find("url \"model.png\""), std::string::npos);
  EXPECT_NE(wrl.find("solid FALSE"), std::string::npos);
}

TEST(ModelExport, EachFormatRoundTrips) {
  const TexturedModel cube = CubeModel();
  const std::string dir = testing::TempDir("model_export_round_trip");
  WriteTexturedModel(cube, dir, ModelExportOptions());
  // OBJ and VRML: 12 significant digits; PLY: doubles; glTF: floats.
  const std::vector<std::pair<std::string, double>> formats = {
      {"obj", 1e-11}, {"ply", 1e-15}, {"wrl", 1e-11}, {"glb", 1e-7}};
  for (const auto& [extension, tolerance] : formats) {
    SCOPED_TRACE(extension);
    const TexturedModel back = ReadTexturedModel(dir + "/model." + extension);
    ExpectSameModel(cube, back, tolerance);
  }
  // OBJ, PLY and VRML keep the 8 shared vertices; glTF needs one vertex per
  // (vertex, texture coordinate) pair: each cube corner lies on 3 charts.
  EXPECT_EQ(ReadTexturedModel(dir + "/model.obj").mesh.NumVertices(), 8u);
  EXPECT_EQ(ReadTexturedModel(dir + "/model.ply").mesh.NumVertices(), 8u);
  EXPECT_EQ(ReadTexturedModel(dir + "/model.wrl").mesh.NumVertices(), 8u);
  EXPECT_EQ(ReadTexturedModel(dir + "/model.glb").mesh.NumVertices(), 24u);
}

TEST(ModelExport, GlbKeepsAGeoreferencedModelToATenthOfAMillimetre) {
  // A UTM-like datum: single-precision coordinates there step by 6 cm.
  TexturedModel model = GridModel();
  for (auto& p : model.mesh.vertices.positions) {
    p += Eigen::Vector3d(500123.4567, 5250987.6543, 412.3456);
  }
  for (bool y_up : {true, false}) {
    const std::string dir = testing::TempDir("model_export_utm");
    ModelExportOptions options;
    options.obj = options.ply = options.vrml = false;
    options.gltf_y_up = y_up;
    WriteTexturedModel(model, dir, options);
    // (The tolerance is relative to the coordinates' size: 0.1 mm.)
    ExpectSameModel(model,
                    ReadTexturedModel(dir + "/model.glb"),
                    1e-4 / model.mesh.vertices.positions[0].norm());
  }
}

// A georeferenced model says in its .glb where it lies: the CRS and the
// origin its coordinates are relative to (asset.extras.georeference).
TEST(ModelExport, GlbCarriesTheGeoreference) {
  const std::string dir = testing::TempDir("model_export_georeference");
  ModelExportOptions options;
  options.obj = options.ply = options.vrml = false;
  options.georeference_json =
      R"({"source_crs": "WGS84 UTM 48N", "crs": "EPSG:32648", )"
      R"("origin": [372000.0, 1486000.0, 22.0]})";
  WriteTexturedModel(CubeModel(), dir, options);
  const std::string bytes = ReadFileToString(dir + "/model.glb");
  ASSERT_GE(bytes.size(), 20u);
  const nlohmann::json json =
      nlohmann::json::parse(bytes.substr(20, U32(bytes, 12)));
  const nlohmann::json& georeference = json["asset"]["extras"]["georeference"];
  EXPECT_EQ(georeference["crs"], "EPSG:32648");
  EXPECT_EQ(georeference["origin"][1], 1486000.0);
  // Still a model any reader opens.
  EXPECT_EQ(ReadTexturedModel(dir + "/model.glb").mesh.NumFaces(),
            CubeModel().mesh.NumFaces());
}

TEST(ModelExport, GltfSplitsVerticesOnlyWhereTexcoordsDiffer) {
  const TexturedModel grid = GridModel();
  const std::string dir = testing::TempDir("model_export_grid");
  ModelExportOptions options;
  options.stem = "grid";
  WriteTexturedModel(grid, dir, options);
  const TexturedModel back = ReadTexturedModel(dir + "/grid.glb");
  EXPECT_EQ(back.mesh.NumVertices(), grid.mesh.NumVertices());
  ExpectSameModel(grid, back, 1e-7);
}

TEST(ModelExport, GlbIsWellFormed) {
  const std::string dir = testing::TempDir("model_export_glb");
  WriteTexturedModel(CubeModel(), dir, ModelExportOptions());
  const std::string bytes = ReadFileToString(dir + "/model.glb");
  ASSERT_GE(bytes.size(), 28u);
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  EXPECT_EQ(U32(bytes, 4), 2u);
  EXPECT_EQ(U32(bytes, 8), bytes.size());
  const uint32_t json_length = U32(bytes, 12);
  EXPECT_EQ(U32(bytes, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  const size_t bin_header = 20 + json_length;
  ASSERT_LE(bin_header + 8, bytes.size());
  const uint32_t bin_length = U32(bytes, bin_header);
  EXPECT_EQ(U32(bytes, bin_header + 4), 0x004E4942u);  // "BIN\0"
  EXPECT_EQ(bin_length % 4, 0u);
  EXPECT_EQ(bin_header + 8 + bin_length, bytes.size());
  // JSON padding is spaces, so the chunk parses as it stands.
  const nlohmann::json json =
      nlohmann::json::parse(bytes.substr(20, json_length));
  EXPECT_EQ(json["asset"]["version"], "2.0");
  EXPECT_EQ(json["buffers"][0]["byteLength"], bin_length);
  const nlohmann::json& primitive = json["meshes"][0]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 4);
  const nlohmann::json& positions =
      json["accessors"][primitive["attributes"]["POSITION"].get<int>()];
  const nlohmann::json& texcoords =
      json["accessors"][primitive["attributes"]["TEXCOORD_0"].get<int>()];
  const nlohmann::json& indices =
      json["accessors"][primitive["indices"].get<int>()];
  // 6 sides x 4 corners, 12 triangles x 3 corners.
  EXPECT_EQ(positions["count"], 24);
  EXPECT_EQ(texcoords["count"], 24);
  EXPECT_EQ(indices["count"], 36);
  EXPECT_EQ(indices["componentType"], 5125);
  // Positions relative to the model's centre, the node's translation (in
  // glTF's y-up frame: datum x, z, -y).
  const nlohmann::json& translation = json["nodes"][0]["translation"];
  EXPECT_NEAR(positions["min"][0].get<double>() + translation[0].get<double>(),
              10.1,
              1e-6);
  EXPECT_NEAR(positions["max"][2].get<double>() + translation[1].get<double>(),
              4.2,
              1e-6);
  for (const nlohmann::json& view : json["bufferViews"]) {
    EXPECT_EQ(view["byteOffset"].get<size_t>() % 4, 0u);
    EXPECT_LE(
        view["byteOffset"].get<size_t>() + view["byteLength"].get<size_t>(),
        bin_length);
  }
  const nlohmann::json& material = json["materials"][0];
  EXPECT_EQ(material["doubleSided"], true);
  EXPECT_EQ(material["pbrMetallicRoughness"]["metallicFactor"], 0.0);
  const nlohmann::json& image = json["images"][0];
  EXPECT_EQ(image["mimeType"], "image/png");
  const nlohmann::json& view =
      json["bufferViews"][image["bufferView"].get<int>()];
  const std::string png =
      bytes.substr(bin_header + 8 + view["byteOffset"].get<size_t>(),
                   view["byteLength"].get<size_t>());
  EXPECT_EQ(png, ReadFileToString(dir + "/model.png"));
}

// A GLB from another writer: two primitives, 16-bit indices, the texture
// coordinates interleaved with the positions (byteStride 20).
TEST(ModelExport, ReadsPlainGlbWithSeveralPrimitives) {
  const TexturedModel grid = GridModel();
  std::string bin;
  auto append = [&bin](const void* data, size_t size) {
    bin.append(static_cast<const char*>(data), size);
  };
  // Primitive 0: the grid's first 9 triangles as a vertex per corner;
  // primitive 1: the other 9.
  std::vector<size_t> view_offsets;
  for (int part = 0; part < 2; ++part) {
    view_offsets.push_back(bin.size());
    for (int f = part * 9; f < part * 9 + 9; ++f) {
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3f p =
            grid.mesh.vertices.positions[grid.mesh.faces[f][k]].cast<float>();
        const Eigen::Vector2f& uv = grid.mesh.face_texcoords[f][k];
        const float record[5] = {p.x(), p.y(), p.z(), uv.x(), 1 - uv.y()};
        append(record, sizeof(record));
      }
    }
    view_offsets.push_back(bin.size());
    for (uint16_t i = 0; i < 27; ++i) append(&i, 2);
    while (bin.size() % 4) bin.push_back('\0');
  }
  std::vector<uchar> png;
  cv::imencode(".png", grid.atlas, png);
  view_offsets.push_back(bin.size());
  bin.append(png.begin(), png.end());
  while (bin.size() % 4) bin.push_back('\0');
  nlohmann::json json;
  json["asset"] = {{"version", "2.0"}};
  json["buffers"] = {{{"byteLength", bin.size()}}};
  json["images"] = {{{"bufferView", 4}, {"mimeType", "image/png"}}};
  json["textures"] = {{{"source", 0}}};
  json["materials"] = {
      {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  for (int part = 0; part < 2; ++part) {
    json["bufferViews"].push_back({{"buffer", 0},
                                   {"byteOffset", view_offsets[2 * part]},
                                   {"byteLength", 27 * 20},
                                   {"byteStride", 20}});
    json["bufferViews"].push_back({{"buffer", 0},
                                   {"byteOffset", view_offsets[2 * part + 1]},
                                   {"byteLength", 54}});
    json["accessors"].push_back({{"bufferView", 2 * part},
                                 {"componentType", 5126},
                                 {"count", 27},
                                 {"type", "VEC3"}});
    json["accessors"].push_back({{"bufferView", 2 * part},
                                 {"byteOffset", 12},
                                 {"componentType", 5126},
                                 {"count", 27},
                                 {"type", "VEC2"}});
    json["accessors"].push_back({{"bufferView", 2 * part + 1},
                                 {"componentType", 5123},
                                 {"count", 27},
                                 {"type", "SCALAR"}});
    json["meshes"][0]["primitives"].push_back(
        {{"attributes", {{"POSITION", 3 * part}, {"TEXCOORD_0", 3 * part + 1}}},
         {"indices", 3 * part + 2},
         {"material", 0}});
  }
  json["bufferViews"].push_back({{"buffer", 0},
                                 {"byteOffset", view_offsets[4]},
                                 {"byteLength", png.size()}});
  const std::string dir = testing::TempDir("model_export_plain");
  auto write_glb = [&](const nlohmann::json& content, const std::string& name) {
    std::string json_text = content.dump();
    while (json_text.size() % 4) json_text.push_back(' ');
    std::string glb = "glTF";
    auto u32 = [&glb](uint32_t value) { glb.append((const char*)&value, 4); };
    u32(2);
    u32(uint32_t(12 + 8 + json_text.size() + 8 + bin.size()));
    u32(uint32_t(json_text.size()));
    u32(0x4E4F534Au);
    glb += json_text;
    u32(uint32_t(bin.size()));
    u32(0x004E4942u);
    glb += bin;
    WriteFileAtomically(dir + "/" + name, glb);
    return dir + "/" + name;
  };

  const TexturedModel back = ReadTexturedModel(write_glb(json, "x.glb"));
  EXPECT_EQ(back.mesh.NumVertices(), 54u);
  ExpectSameModel(grid, back, 1e-7);

  // A negative stride (read as 2^64 - 8) or a count that would wrap the
  // size check must not read outside the buffer.
  nlohmann::json bad_stride = json;
  bad_stride["bufferViews"][0]["byteStride"] = -8;
  EXPECT_THROW(ReadTexturedModel(write_glb(bad_stride, "stride.glb")),
               InputError);
  nlohmann::json bad_count = json;
  bad_count["accessors"][0]["count"] = (uint64_t(1) << 62) + 1;
  EXPECT_THROW(ReadTexturedModel(write_glb(bad_count, "count.glb")),
               InputError);
}

TEST(ModelExport, ReadsObjVariants) {
  const std::string dir = testing::TempDir("model_export_obj");
  cv::imwrite(dir + "/tex.png", cv::Mat(4, 4, CV_8UC3, cv::Scalar(1, 2, 3)));
  WriteFileAtomically(dir + "/lib.mtl",
                      "newmtl a\nKd 1 1 1\nmap_Kd -clamp on tex.png\n");
  // A quad by negative indices with v/vt/vn corners, then a triangle by
  // positive ones.
  WriteFileAtomically(dir + "/m.obj",
                      "mtllib lib.mtl\n"
                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                      "vn 0 0 1\n"
                      "usemtl a\n"
                      "f -5/-4/1 -4/-3/1 -3/-2/1 -2/-1/1\n"
                      "f 1/1 2/2 5/4\n");
  const TexturedModel model = ReadTexturedModel(dir + "/m.obj");
  ASSERT_EQ(model.mesh.NumFaces(), 3u);
  EXPECT_EQ(model.mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(model.mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(model.mesh.faces[2], Eigen::Vector3i(0, 1, 4));
  EXPECT_EQ(model.mesh.face_texcoords[1][2], Eigen::Vector2f(0, 1));
  EXPECT_EQ(model.atlas.at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));

  // Without texture coordinates (v and v//vn corners): no atlas.
  WriteFileAtomically(dir + "/plain.obj",
                      "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvn 0 0 "
                      "1\nf 1//1 2//1 3//1\n");
  const TexturedModel plain = ReadTexturedModel(dir + "/plain.obj");
  EXPECT_EQ(plain.mesh.NumFaces(), 1u);
  EXPECT_FALSE(plain.mesh.HasTexcoords());
  EXPECT_TRUE(plain.atlas.empty());
  ASSERT_TRUE(plain.mesh.vertices.HasColors());
  EXPECT_EQ(plain.mesh.vertices.colors[1][1], 255);
}

// Throws InputError whose message names `path`.
void ExpectInputError(const std::string& path, const std::string& what) {
  try {
    ReadTexturedModel(path);
    ADD_FAILURE() << what << ": no error for " << path;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(fs::path(path).filename()),
              std::string::npos)
        << what << ": " << error.what();
  }
}

TEST(ModelExport, CorruptFilesAreInputErrors) {
  const std::string dir = testing::TempDir("model_export_corrupt");
  WriteTexturedModel(CubeModel(), dir, ModelExportOptions());
  auto write_cut = [&](const std::string& extension, double share) {
    const std::string bytes = ReadFileToString(dir + "/model." + extension);
    const std::string path = dir + "/cut." + extension;
    WriteFileAtomically(path, bytes.substr(0, size_t(bytes.size() * share)));
    return path;
  };
  ExpectInputError(write_cut("glb", 0.6), "truncated glb");
  ExpectInputError(write_cut("glb", 0.01), "glb without a header");
  ExpectInputError(write_cut("ply", 0.7), "truncated ply");
  ExpectInputError(write_cut("wrl", 0.5), "truncated wrl");
  ExpectInputError(write_cut("obj", 0.0), "empty obj");
  ExpectInputError(dir + "/missing.obj", "missing file");

  // An index past the vertices, patched into a well-formed GLB.
  std::string glb = ReadFileToString(dir + "/model.glb");
  const uint32_t json_length = U32(glb, 12);
  const nlohmann::json json =
      nlohmann::json::parse(glb.substr(20, json_length));
  const size_t index_view = json["accessors"][2]["bufferView"].get<size_t>();
  const size_t at = 20 + json_length + 8 +
                    json["bufferViews"][index_view]["byteOffset"].get<size_t>();
  const uint32_t bad = 1000;
  std::memcpy(&glb[at], &bad, 4);
  WriteFileAtomically(dir + "/bad_index.glb", glb);
  ExpectInputError(dir + "/bad_index.glb", "index out of range");
  // JSON that is not glTF's.
  std::string garbage = ReadFileToString(dir + "/model.glb");
  garbage.replace(20, 8, "{\"x\":[1]");
  WriteFileAtomically(dir + "/garbage.glb", garbage);
  ExpectInputError(dir + "/garbage.glb", "broken JSON");

  // OBJ: a face past the vertices; a texture that is not there.
  WriteFileAtomically(dir + "/bad_face.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
  ExpectInputError(dir + "/bad_face.obj", "face index");
  WriteFileAtomically(dir + "/no_tex.mtl", "newmtl a\nmap_Kd gone.png\n");
  WriteFileAtomically(dir + "/no_tex.obj",
                      "mtllib no_tex.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 "
                      "0\nvt 0 0\nf 1/1 2/1 3/1\n");
  ExpectInputError(dir + "/no_tex.obj", "missing texture");
  ExpectInputError(dir + "/model.png", "unknown format");
}

TEST(ModelExport, RefusesModelsWithoutTexture) {
  const std::string dir = testing::TempDir("model_export_refused");
  TexturedModel no_uv = CubeModel();
  no_uv.mesh.face_texcoords.clear();
  EXPECT_THROW(WriteTexturedModel(no_uv, dir, ModelExportOptions()),
               InputError);
  TexturedModel no_atlas = CubeModel();
  no_atlas.atlas.release();
  EXPECT_THROW(WriteTexturedModel(no_atlas, dir, ModelExportOptions()),
               InputError);
  EXPECT_TRUE(ListFilesRecursive(dir).empty());
}

}  // namespace
}  // namespace bayon

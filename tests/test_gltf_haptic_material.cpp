// The glTF extension MPEG_haptic_material (io/gltf_haptic_material.hpp): written from pictures, read back into
// material maps that equal the pictures' own maps texel for texel, felt on the mesh with the stiffness the picture
// gives; the base model still loads as plain glTF; every named bad input is one FileError; the haptic_material
// tool as a user runs it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "hapticfield/io/gltf.hpp"
#include "hapticfield/io/gltf_haptic_material.hpp"
#include "hapticfield/scenes/model_texture.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "run_seed.hpp"
#ifdef HAPTICFIELD_TOOL_HAPTIC_MATERIAL
#include "child_process.hpp"
#endif

using namespace hapticfield;
namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

/// A side x side square sheet in z = 0 (normal +z) with uv (x, y) / side as
/// glTF stores them (v down: 1 - y / side), two triangles.
tinygltf::Model sheet_model(double side) {
  const float s = static_cast<float>(side);
  const std::vector<float> positions{0, 0, 0, s, 0, 0, s, s, 0, 0, s, 0};
  const std::vector<float> uvs{0, 1, 1, 1, 1, 0, 0, 0};
  const std::vector<std::uint16_t> indices{0, 1, 2, 0, 2, 3};
  tinygltf::Model m;
  m.asset.version = "2.0";
  tinygltf::Buffer b;
  const auto append = [&](const void* p, std::size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    b.data.insert(b.data.end(), c, c + n);
  };
  append(positions.data(), positions.size() * 4);
  append(uvs.data(), uvs.size() * 4);
  append(indices.data(), indices.size() * 2);
  b.data.resize(b.data.size() + 2, 0);
  m.buffers.push_back(b);
  const auto view = [&](std::size_t offset, std::size_t length) {
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = offset;
    v.byteLength = length;
    m.bufferViews.push_back(v);
    return static_cast<int>(m.bufferViews.size()) - 1;
  };
  const auto accessor = [&](int v, int component, int type, std::size_t count) {
    tinygltf::Accessor a;
    a.bufferView = v;
    a.componentType = component;
    a.type = type;
    a.count = count;
    m.accessors.push_back(a);
    return static_cast<int>(m.accessors.size()) - 1;
  };
  tinygltf::Primitive p;
  p.attributes["POSITION"] = accessor(view(0, 48), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 4);
  m.accessors.back().minValues = {0, 0, 0};
  m.accessors.back().maxValues = {side, side, 0};
  p.attributes["TEXCOORD_0"] = accessor(view(48, 32), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, 4);
  p.indices = accessor(view(80, 12), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, 6);
  p.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(p);
  m.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  m.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  return m;
}

cv::Mat random_picture(std::mt19937& rng, int depth) {
  std::uniform_int_distribution<int> size(1, 24);
  cv::Mat p(size(rng), size(rng), depth == 16 ? CV_16UC1 : CV_8UC1);
  cv::randu(p, 0, depth == 16 ? 65536 : 256);
  return p;
}

std::string write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

fs::path tmp(const std::string& name) {
  return fs::path(HAPTICFIELD_TEST_TMP) / "gltf_haptic" / name;
}

/// The constructed sheet with one authored material, as .gltf text.
std::string authored_sheet(const io::HapticMaterialPictures& pictures) {
  tinygltf::Model m = sheet_model(0.2);
  (void)io::add_haptic_material(m, pictures);
  return io::write_gltf_string(std::move(m));
}

io::HapticMaterialPictures small_pictures() {
  io::HapticMaterialPictures p;
  p.name = "glass and sandpaper";
  cv::Mat half(4, 4, CV_8UC1, cv::Scalar(0));
  half.colRange(2, 4).setTo(255);
  p.stiffness = {half, 800.0, 2400.0};
  p.friction = {half, 0.1, 0.9};
  cv::Mat relief(32, 32, CV_8UC1, cv::Scalar(0));
  relief.colRange(16, 32).setTo(255);
  p.texture = {relief, 0.0, 0.3};
  cv::Mat ids(2, 2, CV_8UC1, cv::Scalar(1));
  ids.col(1).setTo(2);
  p.vibration_ids = ids;
  p.temperature = io::HapticPicture::constant(30.0);
  return p;
}

}  // namespace

TEST_CASE("MPEG_haptic_material written from random pictures reads back as the same maps, texel for texel",
          "[gltf_haptic]") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  for (int round = 0; round < 12; ++round) {
    io::HapticMaterialPictures p;
    p.name = "m" + std::to_string(round);
    p.stiffness = {random_picture(rng, round % 2 ? 16 : 8), 300.0 + round, 2500.0};
    p.friction = {random_picture(rng, 8), 0.05, 1.2};
    p.texture = {random_picture(rng, 8), 0.0, 0.25};
    cv::Mat ids = random_picture(rng, 8);
    p.vibration_ids = ids;
    const bool binary = round % 3 == 0;
    tinygltf::Model m = sheet_model(0.2);
    (void)io::add_haptic_material(m, p);
    const std::string bytes = io::write_gltf_string(std::move(m), binary);
    CHECK((bytes.substr(0, 4) == "glTF") == binary);
    const io::GltfHapticModel back = io::parse_gltf_haptic(bytes, "round trip");
    REQUIRE(back.haptics.materials.size() == 1);
    REQUIRE(back.haptics.mesh_material == std::vector<int>{0});
    const io::HapticMaterial& h = back.haptics.materials[0];
    CHECK(h.name == p.name);
    const io::HapticMaterialLayers layers = io::haptic_material_layers(h);
    // the oracle: the same pictures turned into maps directly
    const auto stiffness = material::property_map_from_image(p.stiffness.picture, 0, p.stiffness.low, p.stiffness.high);
    const auto friction = material::property_map_from_image(p.friction.picture, 0, p.friction.low, p.friction.high);
    const auto vibration = material::index_map_from_image(ids);
    for (int k = 0; k < 200; ++k) {
      const glm::dvec2 uv{u(rng), u(rng)};
      REQUIRE(layers.maps.stiffness.at(uv) == stiffness.at(uv));
      REQUIRE(layers.maps.static_friction.at(uv) == friction.at(uv));
      REQUIRE(layers.maps.dynamic_friction.at(uv) == friction.at(uv));
      REQUIRE(layers.maps.vibration.at(uv) == vibration.at(uv));
    }
    REQUIRE(layers.texture_picture.size() == p.texture.picture.size());
    CHECK(cv::norm(layers.texture_picture, p.texture.picture, cv::NORM_INF) == 0.0);
    CHECK(layers.texture_force == 0.25);
    CHECK(layers.notes.empty());
    // the base model, read as plain glTF: the extension is not required
    const io::LoadedMesh plain = io::parse_gltf(bytes, "plain");
    CHECK(plain.mesh.triangle_count() == 2);
    if (!binary) {
      const Json j = Json::parse(bytes);
      CHECK(j.at("extensionsUsed") == Json::array({"MPEG_haptic_material"}));
      CHECK_FALSE(j.contains("extensionsRequired"));
      CHECK(j.at("meshes")[0].at("extensions").at("MPEG_haptic_material").at("hapticMaterialIndex") == 0);
    }
  }
}

TEST_CASE("MPEG_haptic_material: the sheet is felt with the stiffness and friction its pictures give",
          "[gltf_haptic]") {
  const io::GltfHapticModel back = io::parse_gltf_haptic(authored_sheet(small_pictures()), "sheet");
  const io::HapticMaterialLayers layers = io::haptic_material_layers(back.haptics.materials[0]);
  CHECK(layers.notes.size() == 1);  // the temperature, kept
  material::ModelTextureConfig config;
  config.texture_gain = layers.texture_force;
  const double metres = material::metres_per_uv(back.model.mesh);
  CHECK_THAT(metres, Catch::Matchers::WithinRel(0.2, 1e-6));
  for (const double x : {0.03, 0.17}) {  // the soft half (u < 0.5) and the stiff half
    auto sheet = material::textured_surface(MeshShape(back.model.mesh), layers.texture_picture, metres,
                                            material::MaterialMap(layers.maps), config);
    Probe probe;
    probe.position = {x, 0.1, 0.001};  // [m], above the sheet
    (void)sheet.force(probe);
    probe.position.z = -0.001;  // 1 mm in
    const glm::dvec3 f = sheet.force(probe);
    const double k = x < 0.1 ? 800.0 : 2400.0;
    CHECK_THAT(f.z, Catch::Matchers::WithinRel(k * 0.001, 1e-6));
    CHECK(sheet.touched_material() == (x < 0.1 ? 1u : 2u));
  }
}

TEST_CASE("MPEG_haptic_material on the Khronos Duck: written, re-read, and the Duck still loads as it was",
          "[gltf_haptic]") {
  const fs::path duck = fs::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data" / "gltf" / "Duck.gltf";
  if (!fs::exists(duck)) {
    WARN("../shared/data/gltf/Duck.gltf absent: skipped");
    return;
  }
  const io::LoadedMesh before = io::load_gltf(duck.string());
  for (const char* name : {"duck_haptic.gltf", "duck_haptic.glb"}) {
    const fs::path out = tmp(name);
    fs::create_directories(out.parent_path());
    io::save_gltf_with_haptic_material(duck.string(), small_pictures(), out.string());
    const io::LoadedMesh plain = io::load_gltf(out.string());
    CHECK(plain.mesh.triangle_count() == before.mesh.triangle_count());
    CHECK(plain.mesh.positions == before.mesh.positions);
    CHECK(plain.mesh.uvs == before.mesh.uvs);
    REQUIRE(plain.base_colour_textures.size() == before.base_colour_textures.size());
    CHECK(plain.base_colour_textures[0] == before.base_colour_textures[0]);  // the picture, byte for byte
    const io::GltfHapticModel back = io::load_gltf_haptic(out.string());
    REQUIRE(back.haptics.materials.size() == 1);
    CHECK(back.haptics.mesh_material == std::vector<int>{0});
    const io::HapticMaterialLayers layers = io::haptic_material_layers(back.haptics.materials[0]);
    CHECK(layers.maps.stiffness.lowest() == 800.0);
    CHECK(layers.maps.stiffness.highest() == 2400.0);
    CHECK(layers.maps.vibration.largest() == 2u);
    std::cout << name << ": " << fs::file_size(out) << " bytes, " << back.model.mesh.triangle_count() << " triangles\n";
  }
}

TEST_CASE("MPEG_haptic_material: a haptic reference to a .hjif beside the file is read; others are kept with a note",
          "[gltf_haptic]") {
  const fs::path dir = tmp("reference");
  fs::create_directories(dir);
  const fs::path seed = fs::path(HAPTICFIELD_SOURCE_DIR) / "tests" / "fuzz" / "corpus_hjif" / "curves.hjif";
  std::ifstream in(seed, std::ios::binary);
  write(dir / "touch.hjif", std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()));
  Json j = Json::parse(authored_sheet(small_pictures()));
  j["extensions"]["MPEG_haptic_material"]["materials"][0]["haptic"] = 0;
  j["extensions"]["MPEG_haptic"] = {{"hapticObjects", Json::array({{{"accessors", Json::array({0})}}})}};
  j["buffers"][0]["extensions"] = {{"MPEG_buffer_circular", {{"media", 0}}}};
  const auto with_uri = [&](const std::string& uri) {
    Json k = j;
    k["extensions"]["MPEG_media"] = {{"media", Json::array({{{"alternatives", Json::array({{{"uri", uri}}})}}})}};
    return write(dir / "model.gltf", k.dump());
  };
  {
    const io::GltfHapticModel m = io::load_gltf_haptic(with_uri("touch.hjif"));
    const io::HapticMaterial& h = m.haptics.materials[0];
    CHECK(h.media_path == (dir / "touch.hjif").string());
    REQUIRE(h.media.has_value());
    CHECK_FALSE(h.media->media.perceptions.empty());
  }
  for (const std::string uri : {"../outside.hjif", "/etc/passwd.hjif", "touch.mp4", "missing.hjif"}) {
    const io::GltfHapticModel m = io::load_gltf_haptic(with_uri(uri));
    CHECK_FALSE(m.haptics.materials[0].media.has_value());
    REQUIRE(m.haptics.notes.size() == 1);
    CHECK(m.haptics.notes[0].find("kept only") != std::string::npos);
  }
}

TEST_CASE("MPEG_haptic_material: each named bad input is one FileError naming the JSON path", "[gltf_haptic]") {
  const Json good = Json::parse(authored_sheet(small_pictures()));
  const auto refused = [&](const std::string& what, auto&& change, const std::string& says) {
    INFO(what);
    Json j = good;
    change(j);
    try {
      (void)io::parse_gltf_haptic(j.dump(), "bad.gltf");
      FAIL("accepted");
    } catch (const FileError& e) {
      CHECK_THAT(e.what(), Catch::Matchers::Contains(says));
    }
  };
  const Json::json_pointer ext("/extensions/MPEG_haptic_material");
  refused(
      "not an object", [&](Json& j) { j[ext] = 3; }, "hapticMaterialIndex: 0 of 0 materials");  // tinygltf drops it
  refused(
      "no materials", [&](Json& j) { j[ext] = Json::object(); }, "has no materials");
  refused(
      "materials not an array", [&](Json& j) { j[ext]["materials"] = "x"; }, "materials: is not an array");
  refused(
      "a material not an object", [&](Json& j) { j[ext]["materials"][0] = 1; }, "materials[0]: is not an object");
  refused(
      "stiffness not an array", [&](Json& j) { j[ext]["materials"][0]["stiffness"] = 1; },
      "materials[0].stiffness: is not an array");
  refused(
      "no texture", [&](Json& j) { j[ext]["materials"][0]["stiffness"][0].erase("texture"); }, "has no texture");
  refused(
      "texture index out of range", [&](Json& j) { j[ext]["materials"][0]["stiffness"][0]["texture"]["index"] = 99; },
      "stiffness[0].texture.index: 99 of");
  refused(
      "texture index negative", [&](Json& j) { j[ext]["materials"][0]["friction"][0]["texture"]["index"] = -1; },
      "is negative");
  refused(
      "texture index a string", [&](Json& j) { j[ext]["materials"][0]["friction"][0]["texture"]["index"] = "0"; },
      "is not a whole number");
  refused(
      "unknown type", [&](Json& j) { j[ext]["materials"][0]["vibration"][0]["type"] = "Medium"; },
      "'Medium' is not High_Resolution");
  refused(
      "range not a number", [&](Json& j) { j[ext]["materials"][0]["stiffness"][0]["extras"]["low"] = "soft"; },
      "extras.low: is not a number");
  refused(
      "name not a string", [&](Json& j) { j[ext]["materials"][0]["name"] = 5; }, "name: is not a string");
  refused(
      "mesh index out of range",
      [&](Json& j) { j["meshes"][0]["extensions"]["MPEG_haptic_material"]["hapticMaterialIndex"] = 4; },
      "hapticMaterialIndex: 4 of 1 materials");
  refused(
      "mesh index missing", [&](Json& j) { j["meshes"][0]["extensions"]["MPEG_haptic_material"] = Json::object(); },
      "has no hapticMaterialIndex");
  refused(
      "too many materials",
      [&](Json& j) {
        j[ext]["materials"] = Json::array_t(2000, Json{{"name", "m"}});
      },
      "more than 1024");
  // a texture that is not a picture, and a PNG header that declares 100000 x 100000 px
  std::vector<unsigned char> png(33, 0);
  const unsigned char head[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0,    13,
                                'I',  'H', 'D', 'R', 0,    1,    0x86, 0xA0, 0, 1, 0x86, 0xA0};
  std::memcpy(png.data(), head, sizeof head);
  refused(
      "texture not a picture", [&](Json& j) { j["images"][0]["uri"] = "data:image/png;base64,AAAAAAAA"; },
      "is not a PNG or JPEG picture");
  refused(
      "a huge picture", [&](Json& j) { j["images"][0]["uri"] = "data:image/png;base64," + io::detail::base64(png); },
      "100000 x 100000 pixels");
}

TEST_CASE("MPEG_haptic_material: real files without the extension read as none; the wmtlab scene is one FileError",
          "[gltf_haptic]") {
  const fs::path data = fs::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  const fs::path duck = data / "gltf" / "Duck.gltf";
  if (fs::exists(duck)) {
    const io::GltfHapticModel m = io::load_gltf_haptic(duck.string());
    CHECK(m.haptics.materials.empty());
    CHECK(m.haptics.mesh_material == std::vector<int>{-1});
  }
  const fs::path sd = data / "haptics" / "wmtlab-sd.gltf";  // MPEG_scene_interactivity, no meshes: invalid glTF
  if (fs::exists(sd)) CHECK_THROWS_AS(io::load_gltf_haptic(sd.string()), FileError);
}

#ifdef HAPTICFIELD_TOOL_HAPTIC_MATERIAL
TEST_CASE("haptic_material: --help, authoring from pictures, --info, and one-line errors", "[gltf_haptic][tool]") {
  const std::string tool = HAPTICFIELD_TOOL_HAPTIC_MATERIAL;
  const fs::path dir = tmp("tool");
  fs::create_directories(dir);
  {
    testing::Child c(tool, {"--help"}, dir, "help");
    REQUIRE(c.wait());
    CHECK(c.status() == 0);
    CHECK(c.out().find("usage: haptic_material") != std::string::npos);
  }
  tinygltf::Model m = sheet_model(0.2);
  const std::string base = write(dir / "sheet.gltf", io::write_gltf_string(std::move(m)));
  cv::Mat half(8, 8, CV_8UC1, cv::Scalar(0));
  half.colRange(4, 8).setTo(255);
  const std::string mask = (dir / "mask.png").string();
  REQUIRE(cv::imwrite(mask, half));
  const std::string out = (dir / "out.glb").string();
  {
    testing::Child c(tool,
                     {base, "--out", out, "--stiffness", mask + ":500:2000", "--friction", mask + ":0.2:0.8",
                      "--texture", mask + ":0.4", "--vibration", mask, "--name", "painted"},
                     dir, "author");
    REQUIRE(c.wait());
    CHECK(c.status() == 0);
    CHECK(c.err().find("haptic material 0 written for 1 meshes") != std::string::npos);
  }
  const io::GltfHapticModel back = io::load_gltf_haptic(out);
  REQUIRE(back.haptics.materials.size() == 1);
  const io::HapticMaterialLayers layers = io::haptic_material_layers(back.haptics.materials[0]);
  CHECK(layers.maps.stiffness.at({0.1, 0.5}) == 500.0);
  CHECK(layers.maps.stiffness.at({0.9, 0.5}) == 2000.0);
  CHECK_THAT(layers.maps.static_friction.at({0.9, 0.5}), Catch::Matchers::WithinAbs(0.8, 1e-6));
  CHECK(layers.texture_force == 0.4);
  CHECK(layers.maps.vibration.at({0.9, 0.5}) == 255u);
  {
    testing::Child c(tool, {out, "--info"}, dir, "info");
    REQUIRE(c.wait());
    CHECK(c.status() == 0);
    CHECK(c.out().find("haptic material 0 'painted'") != std::string::npos);
    CHECK(c.out().find("rendered: stiffness 500..2000 N/m") != std::string::npos);
  }
  const auto fails = [&](const std::vector<std::string>& args, int status, const std::string& says) {
    testing::Child c(tool, args, dir, "bad");
    REQUIRE(c.wait());
    CHECK(c.status() == status);
    CHECK(c.err().rfind("haptic_material: ", 0) == 0);
    CHECK(c.err().find(says) != std::string::npos);
    const std::string err = c.err();
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
  };
  fails({base, "--out", out}, 2, "needs at least one of");
  fails({base}, 2, "one of --out PATH or --info is required");
  fails({base, "--out", out, "--stiffness", mask + ":0:10"}, 2, "--stiffness values must be in");
  fails({base, "--out", out, "--friction", mask}, 2, "needs PICTURE:LOW:HIGH");
  fails({base, "--out", out, "--texture", (dir / "missing.png").string() + ":0.5"}, 1, "missing.png");
  fails({(dir / "nothing.gltf").string(), "--info"}, 1, "nothing.gltf");
}
#endif

#pragma once
/// @file gltf_haptic_material.hpp
/// The glTF extension MPEG_haptic_material (ISO/IEC 23090-14 2nd edition,
/// scene description; the public text is the Khronos glTF repository's
/// extensions/2.0/Vendor/MPEG_haptic_material) read into the library's
/// material maps (material/material_map.hpp) and written from pictures.
/// Needs hapticfield::io (tinygltf, OpenCV) and hapticfield::hjif.
///
/// The extension, as its schema defines it:
///   root:  extensions.MPEG_haptic_material.materials[]: each an optional
///          name, `haptic` (an index into MPEG_haptic.hapticObjects, for
///          "Reference" textures) and six arrays of haptic textures:
///          stiffness, friction, vibrotactileTexture, temperature,
///          vibration, custom; each item {texture: textureInfo (index,
///          texCoord), type: High_Resolution | Low_Resolution | Reference |
///          Other}.
///   mesh:  meshes[i].extensions.MPEG_haptic_material.hapticMaterialIndex.
/// The text gives no unit or scale for a texel, so a picture's level t
/// (8-bit: level / 255; 16-bit: level / 65535) means low + (high - low) t:
/// the range is the item's extras {"low", "high"} where present (this
/// library writes them), else HapticMaterialRanges' defaults.
///
/// Reading is setup code (never in a tick). Hostile files: everything the
/// glTF reader checks (io/gltf.hpp), plus every index, type and picture size
/// here; anything wrong is one FileError naming the file and the JSON path.
/// A picture is decoded only after its PNG or JPEG header gives a size
/// within HapticMaterialReadConfig::max_texture_pixels.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <tiny_gltf.h>

#include "hapticfield/core/error.hpp"
#include "hapticfield/io/gltf.hpp"
#include "hapticfield/io/hjif.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/material/material_image.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/material/property_map.hpp"

namespace hapticfield::io {

/// The extension's name, as it appears in extensionsUsed.
inline constexpr std::string_view haptic_material_extension = "MPEG_haptic_material";

/// The `type` of a haptic texture.
enum class HapticTextureKind {
  high_resolution,  ///< "High_Resolution": texel values
  low_resolution,   ///< "Low_Resolution": texel values at a lower resolution
  reference,        ///< "Reference": texel values are ids of haptic signals (a taxel map)
  other,            ///< "Other"
};

/// One item of a property's texture array.
struct HapticTexture {
  HapticTextureKind kind{HapticTextureKind::high_resolution};
  int texture{-1};                                  ///< index into the glTF textures
  int tex_coord{0};                                 ///< TEXCOORD_n it is laid by
  material::UvWrap wrap{material::UvWrap::repeat};  ///< from the texture's sampler (wrapS)
  std::vector<unsigned char> encoded;               ///< the picture's PNG or JPEG bytes
  std::optional<double> low;                        ///< value at level 0 (extras.low)
  std::optional<double> high;                       ///< value at the full level (extras.high)
};

/// One entry of MPEG_haptic_material.materials.
struct HapticMaterial {
  std::string name;
  int haptic{-1};  ///< index into MPEG_haptic.hapticObjects; -1: none
  std::vector<HapticTexture> stiffness;
  std::vector<HapticTexture> friction;
  std::vector<HapticTexture> vibrotactile_texture;
  std::vector<HapticTexture> temperature;
  std::vector<HapticTexture> vibration;
  std::vector<HapticTexture> custom;
  /// The .hjif file the haptic object's media names (its path), when the
  /// chain hapticObjects -> accessor -> buffer (MPEG_buffer_circular) ->
  /// MPEG_media alternative leads to a relative .hjif uri; empty otherwise.
  std::string media_path;
  std::optional<HjifFile> media;  ///< that file, read (HapticMaterialReadConfig::load_media)
};

/// Everything a file's MPEG_haptic_material holds.
struct GltfHapticMaterials {
  std::vector<HapticMaterial> materials;
  std::vector<int> mesh_material;  ///< per glTF mesh: its hapticMaterialIndex, -1 none
  std::vector<std::string> notes;  ///< what is kept without rendering, one line each
};

/// A glTF model and its haptic materials.
struct GltfHapticModel {
  LoadedMesh model;
  GltfHapticMaterials haptics;
};

struct HapticMaterialReadConfig {
  MeshReadConfig mesh{};                                     ///< the glTF reader's limits
  std::uint64_t max_texture_pixels{std::uint64_t{1} << 24};  ///< width x height of one picture
  std::size_t max_materials{1024};                           ///< entries of materials[]
  std::size_t max_textures_per_property{64};                 ///< items of one texture array
  bool load_media{true};                                     ///< read the .hjif a haptic reference names
  HjifLimits hjif{};
};

/// A property's range: level 0 gives low, the full level gives high.
struct HapticRange {
  double low{0.0};
  double high{1.0};
};

/// The ranges used when a texture has no extras.low / extras.high.
struct HapticMaterialRanges {
  HapticRange stiffness{200.0, 3000.0};  ///< [N/m]
  HapticRange friction{0.0, 1.0};        ///< mu_s = mu_k [-]
  HapticRange texture{0.0, 0.5};         ///< high: the tangible-image force at a black/white edge [N]
};

/// What the library renders of one haptic material: its maps and the
/// picture felt as its texture (vibrotactileTexture).
struct HapticMaterialLayers {
  material::MaterialMaps maps;
  cv::Mat texture_picture;         ///< decoded vibrotactileTexture (empty: none)
  double texture_force{0.0};       ///< [N] at a black/white edge of texture_picture
  std::vector<std::string> notes;  ///< what of the material is not rendered
};

namespace detail {

[[nodiscard]] inline const char* haptic_texture_kind_name(HapticTextureKind k) noexcept {
  switch (k) {
    case HapticTextureKind::low_resolution:
      return "Low_Resolution";
    case HapticTextureKind::reference:
      return "Reference";
    case HapticTextureKind::other:
      return "Other";
    default:
      return "High_Resolution";
  }
}

/// Width and height from a PNG (IHDR) or JPEG (SOFn) header; false when
/// the bytes are neither or the header is cut off.
[[nodiscard]] inline bool encoded_picture_size(const std::vector<unsigned char>& b, std::uint64_t& width,
                                               std::uint64_t& height) noexcept {
  const auto be16 = [&](std::size_t i) { return std::uint64_t(b[i]) << 8 | b[i + 1]; };
  const auto be32 = [&](std::size_t i) { return be16(i) << 16 | be16(i + 2); };
  static constexpr unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() >= 24 && std::equal(png, png + 8, b.begin())) {
    width = be32(16);
    height = be32(20);
    return true;
  }
  if (b.size() < 4 || b[0] != 0xFF || b[1] != 0xD8) return false;
  std::size_t at = 2;
  while (at + 4 <= b.size()) {
    if (b[at] != 0xFF) return false;
    const unsigned char marker = b[at + 1];
    if (marker == 0xFF) {
      ++at;
      continue;
    }
    const std::uint64_t length = be16(at + 2);
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (at + 9 > b.size()) return false;
      height = be16(at + 5);
      width = be16(at + 7);
      return true;
    }
    if (length < 2) return false;
    at += 2 + static_cast<std::size_t>(length);
  }
  return false;
}

/// Reads MPEG_haptic_material from a tinygltf model.
class HapticMaterialReader {
 public:
  HapticMaterialReader(const tinygltf::Model& model, const std::string& name, const std::string& dir,
                       const HapticMaterialReadConfig& config)
      : model_(model), name_(name), dir_(dir), config_(config) {}

  [[nodiscard]] GltfHapticMaterials run() {
    const std::string key(haptic_material_extension);
    for (std::size_t m = 0; m < model_.meshes.size(); ++m) {
      int index = -1;
      if (const auto it = model_.meshes[m].extensions.find(key); it != model_.meshes[m].extensions.end()) {
        const std::string where = "meshes[" + std::to_string(m) + "].extensions." + key;
        index = whole(member(it->second, "hapticMaterialIndex", where), where + ".hapticMaterialIndex");
      }
      out_.mesh_material.push_back(index);
    }
    const auto root = model_.extensions.find(key);
    if (root != model_.extensions.end()) {
      const std::string where = "extensions." + key;
      if (!root->second.IsObject()) fail(where, "is not an object");
      const tinygltf::Value& list = member(root->second, "materials", where);
      if (!list.IsArray()) fail(where + ".materials", "is not an array");
      if (list.ArrayLen() > config_.max_materials)
        fail(where + ".materials",
             "has " + std::to_string(list.ArrayLen()) + " entries, more than " + std::to_string(config_.max_materials));
      for (std::size_t i = 0; i < list.ArrayLen(); ++i)
        out_.materials.push_back(
            material(list.Get(static_cast<int>(i)), where + ".materials[" + std::to_string(i) + "]"));
    }
    for (std::size_t m = 0; m < out_.mesh_material.size(); ++m)
      if (out_.mesh_material[m] >= 0 && static_cast<std::size_t>(out_.mesh_material[m]) >= out_.materials.size())
        fail("meshes[" + std::to_string(m) + "].extensions." + key + ".hapticMaterialIndex",
             std::to_string(out_.mesh_material[m]) + " of " + std::to_string(out_.materials.size()) + " materials");
    return std::move(out_);
  }

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& why) const {
    throw mesh_error(name_, where + ": " + why);
  }

  [[nodiscard]] const tinygltf::Value& member(const tinygltf::Value& object, const char* key,
                                              const std::string& where) const {
    if (!object.IsObject()) fail(where, "is not an object");
    if (!object.Has(key)) fail(where, std::string("has no ") + key);
    return object.Get(key);
  }

  [[nodiscard]] int whole(const tinygltf::Value& v, const std::string& where) const {
    if (!v.IsInt()) fail(where, "is not a whole number");
    const int x = v.GetNumberAsInt();
    if (x < 0) fail(where, "is negative");
    return x;
  }

  [[nodiscard]] HapticMaterial material(const tinygltf::Value& v, const std::string& where) {
    if (!v.IsObject()) fail(where, "is not an object");
    HapticMaterial m;
    if (v.Has("name")) {
      if (!v.Get("name").IsString()) fail(where + ".name", "is not a string");
      m.name = v.Get("name").Get<std::string>();
    }
    if (v.Has("haptic")) m.haptic = whole(v.Get("haptic"), where + ".haptic");
    m.stiffness = textures(v, "stiffness", where);
    m.friction = textures(v, "friction", where);
    m.vibrotactile_texture = textures(v, "vibrotactileTexture", where);
    m.temperature = textures(v, "temperature", where);
    m.vibration = textures(v, "vibration", where);
    m.custom = textures(v, "custom", where);
    for (const std::string& k : v.Keys())
      if (k != "name" && k != "haptic" && k != "stiffness" && k != "friction" && k != "vibrotactileTexture" &&
          k != "temperature" && k != "vibration" && k != "custom" && k != "extensions" && k != "extras")
        note(where + "." + k + ": unknown member, skipped");
    if (m.haptic >= 0) resolve_media(m, where);
    return m;
  }

  [[nodiscard]] std::vector<HapticTexture> textures(const tinygltf::Value& material, const char* key,
                                                    const std::string& where) {
    std::vector<HapticTexture> out;
    if (!material.Has(key)) return out;
    const std::string at = where + "." + key;
    const tinygltf::Value& list = material.Get(key);
    if (!list.IsArray()) fail(at, "is not an array");
    if (list.ArrayLen() > config_.max_textures_per_property)
      fail(at, "has " + std::to_string(list.ArrayLen()) + " textures, more than " +
                   std::to_string(config_.max_textures_per_property));
    for (std::size_t i = 0; i < list.ArrayLen(); ++i)
      out.push_back(texture(list.Get(static_cast<int>(i)), at + "[" + std::to_string(i) + "]"));
    return out;
  }

  [[nodiscard]] std::optional<double> number_in_extras(const tinygltf::Value& item, const char* key,
                                                       const std::string& where) const {
    if (!item.Has("extras") || !item.Get("extras").IsObject() || !item.Get("extras").Has(key)) return std::nullopt;
    const tinygltf::Value& v = item.Get("extras").Get(key);
    if (!v.IsNumber()) fail(where + ".extras." + key, "is not a number");
    const double x = v.GetNumberAsDouble();
    if (!std::isfinite(x)) fail(where + ".extras." + key, "is not finite");
    return x;
  }

  [[nodiscard]] HapticTexture texture(const tinygltf::Value& item, const std::string& where) {
    if (!item.IsObject()) fail(where, "is not an object");
    HapticTexture t;
    const tinygltf::Value& info = member(item, "texture", where);
    t.texture = whole(member(info, "index", where + ".texture"), where + ".texture.index");
    if (info.Has("texCoord")) t.tex_coord = whole(info.Get("texCoord"), where + ".texture.texCoord");
    const tinygltf::Value& type = member(item, "type", where);
    if (!type.IsString()) fail(where + ".type", "is not a string");
    const std::string kind = type.Get<std::string>();
    if (kind == "High_Resolution")
      t.kind = HapticTextureKind::high_resolution;
    else if (kind == "Low_Resolution")
      t.kind = HapticTextureKind::low_resolution;
    else if (kind == "Reference")
      t.kind = HapticTextureKind::reference;
    else if (kind == "Other")
      t.kind = HapticTextureKind::other;
    else
      fail(where + ".type", "'" + kind.substr(0, 40) + "' is not High_Resolution, Low_Resolution, Reference or Other");
    t.low = number_in_extras(item, "low", where);
    t.high = number_in_extras(item, "high", where);
    if (static_cast<std::size_t>(t.texture) >= model_.textures.size())
      fail(where + ".texture.index",
           std::to_string(t.texture) + " of " + std::to_string(model_.textures.size()) + " textures");
    const tinygltf::Texture& tex = model_.textures[static_cast<std::size_t>(t.texture)];
    if (tex.sampler >= 0 && static_cast<std::size_t>(tex.sampler) < model_.samplers.size())
      t.wrap = model_.samplers[static_cast<std::size_t>(tex.sampler)].wrapS == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE
                   ? material::UvWrap::clamp
                   : material::UvWrap::repeat;
    if (tex.source < 0 || static_cast<std::size_t>(tex.source) >= model_.images.size())
      fail(where + ".texture.index", "texture " + std::to_string(t.texture) + " has no image");
    t.encoded = model_.images[static_cast<std::size_t>(tex.source)].image;
    std::uint64_t w = 0;
    std::uint64_t h = 0;
    if (!encoded_picture_size(t.encoded, w, h))
      fail(where, "texture " + std::to_string(t.texture) + " is not a PNG or JPEG picture");
    if (w == 0 || h == 0 || w > config_.max_texture_pixels / h)
      fail(where, "texture " + std::to_string(t.texture) + " is " + std::to_string(w) + " x " + std::to_string(h) +
                      " pixels (at most " + std::to_string(config_.max_texture_pixels) + ")");
    return t;
  }

  /// hapticObjects[haptic].accessors[0] -> bufferView -> buffer's
  /// MPEG_buffer_circular.media -> MPEG_media.media[].alternatives[0].uri.
  void resolve_media(HapticMaterial& m, const std::string& where) {
    const std::string why = where + ".haptic " + std::to_string(m.haptic);
    const auto fail_note = [&](const std::string& what) { note(why + ": " + what + "; the reference is kept only"); };
    const auto haptic = model_.extensions.find("MPEG_haptic");
    if (haptic == model_.extensions.end() || !haptic->second.IsObject() || !haptic->second.Has("hapticObjects"))
      return fail_note("the file has no MPEG_haptic.hapticObjects");
    const tinygltf::Value& objects = haptic->second.Get("hapticObjects");
    if (!objects.IsArray() || static_cast<std::size_t>(m.haptic) >= objects.ArrayLen())
      return fail_note("no such haptic object");
    const tinygltf::Value& object = objects.Get(m.haptic);
    if (!object.IsObject() || !object.Has("accessors") || !object.Get("accessors").IsArray() ||
        object.Get("accessors").ArrayLen() == 0 || !object.Get("accessors").Get(0).IsInt())
      return fail_note("the haptic object names no accessor");
    const int accessor = object.Get("accessors").Get(0).GetNumberAsInt();
    if (accessor < 0 || static_cast<std::size_t>(accessor) >= model_.accessors.size())
      return fail_note("no such accessor");
    const int view = model_.accessors[static_cast<std::size_t>(accessor)].bufferView;
    if (view < 0 || static_cast<std::size_t>(view) >= model_.bufferViews.size())
      return fail_note("the accessor has no buffer view");
    const int buffer = model_.bufferViews[static_cast<std::size_t>(view)].buffer;
    if (buffer < 0 || static_cast<std::size_t>(buffer) >= model_.buffers.size()) return fail_note("no such buffer");
    const auto& exts = model_.buffers[static_cast<std::size_t>(buffer)].extensions;
    const auto circular = exts.find("MPEG_buffer_circular");
    if (circular == exts.end() || !circular->second.IsObject() || !circular->second.Has("media") ||
        !circular->second.Get("media").IsInt())
      return fail_note("the buffer has no MPEG_buffer_circular.media");
    const int media = circular->second.Get("media").GetNumberAsInt();
    const auto mpeg_media = model_.extensions.find("MPEG_media");
    if (mpeg_media == model_.extensions.end() || !mpeg_media->second.IsObject() || !mpeg_media->second.Has("media") ||
        !mpeg_media->second.Get("media").IsArray() || media < 0 ||
        static_cast<std::size_t>(media) >= mpeg_media->second.Get("media").ArrayLen())
      return fail_note("no such MPEG_media entry");
    const tinygltf::Value& entry = mpeg_media->second.Get("media").Get(media);
    if (!entry.IsObject() || !entry.Has("alternatives") || !entry.Get("alternatives").IsArray() ||
        entry.Get("alternatives").ArrayLen() == 0 || !entry.Get("alternatives").Get(0).IsObject() ||
        !entry.Get("alternatives").Get(0).Has("uri") || !entry.Get("alternatives").Get(0).Get("uri").IsString())
      return fail_note("the media has no alternative with a uri");
    const std::string uri = entry.Get("alternatives").Get(0).Get("uri").Get<std::string>();
    std::string lower = uri;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    if (lower.size() < 5 || lower.substr(lower.size() - 5) != ".hjif")
      return fail_note("the media '" + uri.substr(0, 80) + "' is not a .hjif file");
    const std::filesystem::path rel(uri);
    if (dir_.empty() || rel.is_absolute() || rel.has_root_name() || rel.has_root_directory())
      return fail_note("the media '" + uri.substr(0, 80) + "' is not a path relative to the glTF file");
    const std::string path = (std::filesystem::path(dir_) / rel).string();
    if (!inside_folder(dir_, path))
      return fail_note("the media '" + uri.substr(0, 80) + "' is outside the file's folder");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      return fail_note("the media '" + uri.substr(0, 80) + "' is missing");
    m.media_path = path;
    if (config_.load_media) m.media = load_hjif(path, config_.hjif);
  }

  void note(std::string line) {
    if (out_.notes.size() < 64 && std::find(out_.notes.begin(), out_.notes.end(), line) == out_.notes.end())
      out_.notes.push_back(std::move(line));
  }

  const tinygltf::Model& model_;
  const std::string& name_;
  const std::string& dir_;
  const HapticMaterialReadConfig& config_;
  GltfHapticMaterials out_;
};

[[nodiscard]] inline std::string base64(const std::vector<unsigned char>& bytes) {
  static constexpr char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = std::uint32_t(bytes[i]) << 16 |
                            (i + 1 < bytes.size() ? std::uint32_t(bytes[i + 1]) << 8 : 0) |
                            (i + 2 < bytes.size() ? std::uint32_t(bytes[i + 2]) : 0);
    out += digits[n >> 18 & 63];
    out += digits[n >> 12 & 63];
    out += i + 1 < bytes.size() ? digits[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? digits[n & 63] : '=';
  }
  return out;
}

/// tinygltf's image writer, replaced: the kept encoded bytes as a data uri
/// (nothing is decoded, re-encoded or written beside the file).
inline bool embed_kept_image(const std::string*, const std::string*, const tinygltf::Image* image, bool,
                             std::string* out_uri, void*) {
  if (image == nullptr || image->image.empty() || out_uri == nullptr) return false;
  const bool png = image->image.size() >= 4 && image->image[0] == 0x89 && image->image[1] == 'P';
  *out_uri = std::string(png ? "data:image/png;base64," : "data:image/jpeg;base64,") + base64(image->image);
  return true;
}

}  // namespace detail

/// Reads a .gltf or .glb in memory and its MPEG_haptic_material.
/// @param resource_dir  folder of external buffers, images and .hjif media
///                      (never outside it); empty: only embedded data
/// @throws FileError for anything parse_gltf() refuses, and for a wrong
///         type, a missing required member, an index out of range, a
///         texture that is not a PNG or JPEG, or a picture larger than
///         config.max_texture_pixels in the extension; a named .hjif that
///         load_hjif() refuses.
[[nodiscard]] inline GltfHapticModel parse_gltf_haptic(std::string_view bytes, const std::string& name,
                                                       const HapticMaterialReadConfig& config = {},
                                                       const std::string& resource_dir = {}) {
  std::string warn;
  const tinygltf::Model model = read_gltf_model(bytes, name, config.mesh, resource_dir, warn);
  GltfHapticModel out;
  detail::add_reader_warnings(out.model, warn);
  detail::GltfReader reader(model, name, config.mesh, out.model);
  reader.run();
  detail::finish_mesh(out.model, name, config.mesh, reader.take_normal_missing());
  out.haptics = detail::HapticMaterialReader(model, name, resource_dir, config).run();
  return out;
}

/// parse_gltf_haptic() of a file, with its external files from its folder.
/// @throws FileError as parse_gltf_haptic(), or for a missing, unreadable
///         or too large file.
[[nodiscard]] inline GltfHapticModel load_gltf_haptic(const std::string& path,
                                                      const HapticMaterialReadConfig& config = {}) {
  detail::check_config(config.mesh);
  const std::string bytes = read_file(path, config.mesh.max_file_bytes);
  return parse_gltf_haptic(bytes, path, config, detail::folder_of(path));
}

/// A haptic texture's picture, decoded as the file holds it (1, 3 or 4
/// channels; 8 or 16 bits).
/// @throws FileError when OpenCV cannot decode it.
[[nodiscard]] inline cv::Mat decode_haptic_texture(const HapticTexture& t) {
  cv::Mat picture;
  try {
    if (!t.encoded.empty())
      picture = cv::imdecode(
          cv::Mat(1, static_cast<int>(t.encoded.size()), CV_8UC1, const_cast<unsigned char*>(t.encoded.data())),
          cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw FileError("haptic texture " + std::to_string(t.texture) + ": cannot decode: " + e.what());
  }
  if (picture.empty())
    throw FileError("haptic texture " + std::to_string(t.texture) + ": not a picture OpenCV decodes");
  return picture;
}

namespace detail {

/// The channel a haptic value is read from: the only one, or red (OpenCV
/// orders colours blue, green, red), as the texel's first glTF channel.
[[nodiscard]] inline int value_channel(const cv::Mat& picture) noexcept {
  return picture.channels() >= 3 ? 2 : 0;
}

/// The texture of a list the library renders: the first High_Resolution,
/// else Low_Resolution, else Other, laid by TEXCOORD_0; nullptr if none.
[[nodiscard]] inline const HapticTexture* rendered_texture(const std::vector<HapticTexture>& list) noexcept {
  for (const HapticTextureKind k :
       {HapticTextureKind::high_resolution, HapticTextureKind::low_resolution, HapticTextureKind::other})
    for (const HapticTexture& t : list)
      if (t.kind == k && t.tex_coord == 0) return &t;
  return nullptr;
}

[[nodiscard]] inline material::PropertyMap property_of(const HapticTexture& t, HapticRange range) {
  const cv::Mat picture = decode_haptic_texture(t);
  return material::property_map_from_image(picture, value_channel(picture), t.low.value_or(range.low),
                                           t.high.value_or(range.high), material::UvLayout{t.wrap});
}

}  // namespace detail

/// What the library renders of a haptic material (docs/materials.md lists
/// every field):
///  - stiffness: the first High_Resolution (else Low_Resolution, else
///    Other) texture on TEXCOORD_0 -> MaterialMaps::stiffness, bilinear;
///  - friction: the same -> static and dynamic friction (one coefficient);
///  - vibrotactileTexture: the same -> texture_picture, felt as a
///    tangible-image texture with texture_force = its range's high [N];
///  - vibration: a Reference texture -> MaterialMaps::vibration (texel
///    levels as the vibration tap's material ids, nearest texel);
///  - temperature, custom, the rest and other texture coordinates: kept in
///    HapticMaterial, named in notes.
/// @throws FileError for a picture that does not decode;
///         std::invalid_argument for a range that makes a stiffness <= 0 or
///         a friction < 0.
[[nodiscard]] inline HapticMaterialLayers haptic_material_layers(const HapticMaterial& m,
                                                                 const HapticMaterialRanges& ranges = {}) {
  HapticMaterialLayers out;
  const auto kept = [&](const std::vector<HapticTexture>& list, const char* what, const HapticTexture* used) {
    for (const HapticTexture& t : list)
      if (&t != used)
        out.notes.push_back(std::string(what) + ": texture " + std::to_string(t.texture) + " (" +
                            detail::haptic_texture_kind_name(t.kind) +
                            (t.tex_coord != 0 ? ", TEXCOORD_" + std::to_string(t.tex_coord) : std::string()) +
                            ") kept, not rendered");
  };
  const HapticTexture* stiffness = detail::rendered_texture(m.stiffness);
  if (stiffness != nullptr) {
    out.maps.stiffness = detail::property_of(*stiffness, ranges.stiffness);
    if (!(out.maps.stiffness.lowest() > 0.0))
      throw std::invalid_argument("haptic material '" + m.name + "': its stiffness range gives " +
                                  std::to_string(out.maps.stiffness.lowest()) + " N/m, not > 0");
  }
  kept(m.stiffness, "stiffness", stiffness);
  const HapticTexture* friction = detail::rendered_texture(m.friction);
  if (friction != nullptr) {
    out.maps.static_friction = detail::property_of(*friction, ranges.friction);
    out.maps.dynamic_friction = out.maps.static_friction;
  }
  kept(m.friction, "friction", friction);
  const HapticTexture* texture = detail::rendered_texture(m.vibrotactile_texture);
  if (texture != nullptr) {
    out.texture_picture = decode_haptic_texture(*texture);
    out.texture_force = texture->high.value_or(ranges.texture.high);
    if (!std::isfinite(out.texture_force) || out.texture_force < 0.0)
      throw std::invalid_argument("haptic material '" + m.name + "': its texture force must be >= 0 N");
  }
  kept(m.vibrotactile_texture, "vibrotactileTexture", texture);
  const HapticTexture* vibration = nullptr;
  for (const HapticTexture& t : m.vibration)
    if (t.kind == HapticTextureKind::reference && t.tex_coord == 0) {
      vibration = &t;
      break;
    }
  if (vibration != nullptr) {
    const cv::Mat ids = decode_haptic_texture(*vibration);
    try {
      out.maps.vibration =
          material::index_map_from_image(ids, detail::value_channel(ids), material::UvLayout{vibration->wrap});
    } catch (const std::invalid_argument& e) {
      throw FileError(std::string("haptic material '") + m.name + "': vibration ids: " + e.what());
    }
  }
  kept(m.vibration, "vibration", vibration);
  kept(m.temperature, "temperature", nullptr);
  kept(m.custom, "custom", nullptr);
  if (m.haptic >= 0)
    out.notes.push_back("haptic object " + std::to_string(m.haptic) +
                        (m.media ? " (" + m.media_path + ") read, played through the .hjif path, not the material"
                                 : " kept, not rendered"));
  return out;
}

/// One property authored from a picture: its level t gives low + (high -
/// low) t. An empty picture: the property is not written.
struct HapticPicture {
  cv::Mat picture;  ///< 8- or 16-bit, 1 channel (else its red channel is used)
  double low{0.0};
  double high{1.0};
  /// A constant: a 1 x 1 picture with low = high = value.
  [[nodiscard]] static HapticPicture constant(double value) {
    return {cv::Mat(1, 1, CV_8UC1, cv::Scalar(0)), value, value};
  }
};

/// A haptic material authored from pictures (HapticMaterialLayers' meaning:
/// stiffness [N/m], friction [-], texture: high = its force [N]; vibration:
/// an id picture, 8 or 16 bit, its levels the vibration material ids).
struct HapticMaterialPictures {
  std::string name;
  HapticPicture stiffness;
  HapticPicture friction;
  HapticPicture texture;
  cv::Mat vibration_ids;
  HapticPicture temperature;  ///< kept by readers, not rendered here [degrees C]
};

namespace detail {

[[nodiscard]] inline std::vector<unsigned char> png_of(const cv::Mat& picture, const char* what) {
  if (picture.empty()) return {};
  if (picture.depth() != CV_8U && picture.depth() != CV_16U)
    throw std::invalid_argument(std::string("haptic material: the ") + what + " picture must be 8- or 16-bit");
  cv::Mat one = picture;
  if (picture.channels() != 1) cv::extractChannel(picture, one, value_channel(picture));
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", one, png))
    throw std::invalid_argument(std::string("haptic material: cannot encode ") + what);
  return png;
}

}  // namespace detail

/// Adds `pictures` to a tinygltf model as MPEG_haptic_material entry and
/// points every mesh at it (hapticMaterialIndex); extensionsUsed names the
/// extension, extensionsRequired does not, so a viewer still opens the
/// model. The pictures become PNG images embedded on writing.
/// @returns the index of the new entry.
/// @throws std::invalid_argument for a picture that is not 8- or 16-bit or
///         a low or high that is not finite.
inline int add_haptic_material(tinygltf::Model& model, const HapticMaterialPictures& pictures) {
  const std::string key(haptic_material_extension);
  tinygltf::Value::Object entry;
  if (!pictures.name.empty()) entry["name"] = tinygltf::Value(pictures.name);
  int sampler = -1;
  const auto add = [&](const cv::Mat& picture, const char* property, const char* type,
                       std::optional<HapticRange> range) {
    std::vector<unsigned char> png = detail::png_of(picture, property);
    if (png.empty()) return;
    if (range && (!std::isfinite(range->low) || !std::isfinite(range->high)))
      throw std::invalid_argument(std::string("haptic material: the ") + property + " range must be finite");
    if (sampler < 0) {  // nearest texels, repeated: the reader's bilinear read is its own
      tinygltf::Sampler s;
      s.magFilter = TINYGLTF_TEXTURE_FILTER_NEAREST;
      s.minFilter = TINYGLTF_TEXTURE_FILTER_NEAREST;
      s.name = "haptic";
      model.samplers.push_back(s);
      sampler = static_cast<int>(model.samplers.size()) - 1;
    }
    tinygltf::Image image;
    image.name = std::string("haptic_") + property;
    image.mimeType = "image/png";
    image.image = std::move(png);
    model.images.push_back(std::move(image));
    tinygltf::Texture texture;
    texture.source = static_cast<int>(model.images.size()) - 1;
    texture.sampler = sampler;
    model.textures.push_back(texture);
    tinygltf::Value::Object info;
    info["index"] = tinygltf::Value(static_cast<int>(model.textures.size()) - 1);
    tinygltf::Value::Object item;
    item["texture"] = tinygltf::Value(std::move(info));
    item["type"] = tinygltf::Value(std::string(type));
    if (range) {
      tinygltf::Value::Object extras;
      extras["low"] = tinygltf::Value(range->low);
      extras["high"] = tinygltf::Value(range->high);
      item["extras"] = tinygltf::Value(std::move(extras));
    }
    tinygltf::Value::Array list;
    list.push_back(tinygltf::Value(std::move(item)));
    entry[property] = tinygltf::Value(std::move(list));
  };
  const auto range_of = [](const HapticPicture& p) { return std::optional<HapticRange>(HapticRange{p.low, p.high}); };
  add(pictures.stiffness.picture, "stiffness", "High_Resolution", range_of(pictures.stiffness));
  add(pictures.friction.picture, "friction", "High_Resolution", range_of(pictures.friction));
  add(pictures.texture.picture, "vibrotactileTexture", "High_Resolution", range_of(pictures.texture));
  add(pictures.temperature.picture, "temperature", "High_Resolution", range_of(pictures.temperature));
  add(pictures.vibration_ids, "vibration", "Reference", std::nullopt);

  tinygltf::Value::Array materials;
  if (const auto it = model.extensions.find(key); it != model.extensions.end() && it->second.IsObject() &&
                                                  it->second.Has("materials") && it->second.Get("materials").IsArray())
    materials = it->second.Get("materials").Get<tinygltf::Value::Array>();
  materials.push_back(tinygltf::Value(std::move(entry)));
  const int index = static_cast<int>(materials.size()) - 1;
  tinygltf::Value::Object root;
  root["materials"] = tinygltf::Value(std::move(materials));
  model.extensions[key] = tinygltf::Value(std::move(root));
  for (tinygltf::Mesh& mesh : model.meshes) {
    tinygltf::Value::Object ref;
    ref["hapticMaterialIndex"] = tinygltf::Value(index);
    mesh.extensions[key] = tinygltf::Value(std::move(ref));
  }
  if (std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), key) == model.extensionsUsed.end())
    model.extensionsUsed.push_back(key);
  model.extensionsRequired.erase(std::remove(model.extensionsRequired.begin(), model.extensionsRequired.end(), key),
                                 model.extensionsRequired.end());
  return index;
}

/// The model as one self-contained .gltf text (buffers and images embedded
/// as data uris), or .glb bytes when `binary`.
/// @throws FileError when tinygltf cannot serialise it.
[[nodiscard]] inline std::string write_gltf_string(tinygltf::Model model, bool binary = false) {
  for (tinygltf::Buffer& b : model.buffers)
    b.uri.clear();  // embedded (or the .glb BIN chunk)
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(&detail::embed_kept_image, nullptr);
  std::ostringstream out;
  if (!writer.WriteGltfSceneToStream(&model, out, !binary, binary)) throw FileError("cannot serialise the glTF model");
  return out.str();
}

/// Reads the glTF at `base` (its buffers and images from its folder), adds
/// the material from `pictures` for every mesh and writes a
/// self-contained .gltf (or .glb, by the extension of `path`).
/// @throws FileError for a base file parse_gltf() refuses or an output that
///         cannot be written; std::invalid_argument as add_haptic_material().
inline void save_gltf_with_haptic_material(const std::string& base, const HapticMaterialPictures& pictures,
                                           const std::string& path, const MeshReadConfig& config = {}) {
  detail::check_config(config);
  const std::string bytes = read_file(base, config.max_file_bytes);
  std::string warn;
  tinygltf::Model model = read_gltf_model(bytes, base, config, detail::folder_of(base), warn);
  (void)add_haptic_material(model, pictures);
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  const std::string text = write_gltf_string(std::move(model), ext == ".glb");
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) throw FileError("cannot write '" + path + "'");
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !ok) throw FileError("cannot write '" + path + "'");
}

}  // namespace hapticfield::io

// haptic_material MODEL.gltf (--out OUT.gltf|OUT.glb [property pictures] | --info)
//
// Authors an MPEG_haptic_material (glTF extension, ISO/IEC 23090-14) from
// pictures and saves the model with it, self-contained; or lists what a
// model's haptic materials hold and what the library renders of them
// (io/gltf_haptic_material.hpp). The extension is named in extensionsUsed,
// not extensionsRequired, so any glTF viewer still opens the model.
//
// Exit status: 0 done, 1 bad input (file, picture), 2 bad usage.
#include <cstdio>
#include <string>

#include "common/cli.hpp"
#include "hapticfield/image/load.hpp"
#include "hapticfield/io/gltf_haptic_material.hpp"

using namespace hapticfield;

namespace {

const char* const usage_text =
    "usage: haptic_material MODEL.gltf --out OUT.gltf [--stiffness PIC:LOW:HIGH] [--friction PIC:LOW:HIGH]\n"
    "                       [--texture PIC:FORCE] [--vibration IDS.png] [--name NAME]\n"
    "       haptic_material MODEL.gltf --info\n"
    "  writes MODEL with an MPEG_haptic_material made of pictures (one channel: gray, or red), for every mesh\n"
    "  --out PATH          the model written self-contained: .gltf (data uris) or .glb\n"
    "  --stiffness P:L:H   picture P, black = L N/m, white = H N/m (L, H > 0)\n"
    "  --friction P:L:H    picture P, black = mu L, white = mu H (static = dynamic; L, H >= 0)\n"
    "  --texture P:F       picture P felt as a tangible-image texture, F N at a black/white edge\n"
    "  --vibration IDS     8- or 16-bit picture whose levels are vibration material ids (lossless: PNG)\n"
    "  --name NAME         the haptic material's name\n"
    "  --info              list the model's haptic materials, field by field, rendered or kept\n"
    "  -h, --help          this text\n"
    "Exit status: 0 done, 1 bad input, 2 bad usage.\n";

struct Args {
  std::string model, out;
  bool info{false};
  io::HapticMaterialPictures pictures;
  bool any{false};
};

/// "PATH:A:B" (b_needed) or "PATH:A" split from the right, so a path may hold ':'.
io::HapticPicture picture_flag(cli::Parser& p, bool two_numbers, cli::Interval range) {
  const std::string flag = p.token();
  const std::string v = p.value();
  std::string path = v;
  double numbers[2] = {0.0, 0.0};
  for (int k = two_numbers ? 1 : 0; k >= 0; --k) {
    const auto colon = path.rfind(':');
    if (colon == std::string::npos || colon == 0)
      throw cli::UsageError(flag + " needs " + (two_numbers ? "PICTURE:LOW:HIGH" : "PICTURE:FORCE") + ", got '" + v +
                            "'");
    numbers[k] = cli::parse_real(path.substr(colon + 1), flag);
    if (!range.contains(numbers[k]))
      throw cli::UsageError(flag + " values must be in " + range.text() + ", got '" + v + "'");
    path.resize(colon);
  }
  io::HapticPicture h;
  h.picture = load_image(path);
  h.low = two_numbers ? numbers[0] : 0.0;
  h.high = two_numbers ? numbers[1] : numbers[0];
  return h;
}

const char* kind_name(io::HapticTextureKind k) {
  return io::detail::haptic_texture_kind_name(k);
}

int info(const Args& a) {
  const io::GltfHapticModel m = io::load_gltf_haptic(a.model);
  std::printf("%s: %zu triangles, %zu haptic materials\n", a.model.c_str(), m.model.mesh.triangle_count(),
              m.haptics.materials.size());
  for (std::size_t i = 0; i < m.haptics.mesh_material.size(); ++i)
    if (m.haptics.mesh_material[i] >= 0) std::printf("mesh %zu: haptic material %d\n", i, m.haptics.mesh_material[i]);
  for (std::size_t i = 0; i < m.haptics.materials.size(); ++i) {
    const io::HapticMaterial& h = m.haptics.materials[i];
    std::printf("haptic material %zu '%s'\n", i, h.name.c_str());
    const auto list = [&](const char* what, const std::vector<io::HapticTexture>& textures) {
      for (const io::HapticTexture& t : textures) {
        std::printf("  %s: texture %d %s", what, t.texture, kind_name(t.kind));
        if (t.low && t.high) std::printf(" range %g..%g", *t.low, *t.high);
        std::printf("\n");
      }
    };
    list("stiffness", h.stiffness);
    list("friction", h.friction);
    list("vibrotactileTexture", h.vibrotactile_texture);
    list("temperature", h.temperature);
    list("vibration", h.vibration);
    list("custom", h.custom);
    const io::HapticMaterialLayers layers = io::haptic_material_layers(h);
    const material::MaterialMaps& maps = layers.maps;
    std::printf("  rendered: stiffness %g..%g N/m, friction %g..%g, texture %s, vibration ids up to %u\n",
                maps.stiffness.lowest(), maps.stiffness.highest(), maps.static_friction.lowest(),
                maps.static_friction.highest(),
                layers.texture_picture.empty() ? "none"
                                               : (std::to_string(layers.texture_picture.cols) + " x " +
                                                  std::to_string(layers.texture_picture.rows) + " px, " +
                                                  cli::detail::number_text(layers.texture_force) + " N")
                                                     .c_str(),
                maps.vibration.largest());
    for (const std::string& n : layers.notes)
      std::printf("  note: %s\n", n.c_str());
  }
  for (const std::string& n : m.haptics.notes)
    std::printf("note: %s\n", n.c_str());
  return cli::exit_ok;
}

int author(const Args& a) {
  io::save_gltf_with_haptic_material(a.model, a.pictures, a.out);
  const io::GltfHapticModel back = io::load_gltf_haptic(a.out);  // what a reader of the file gets
  std::fprintf(stderr, "%s: %zu triangles, haptic material %zu written for %zu meshes\n", a.out.c_str(),
               back.model.mesh.triangle_count(), back.haptics.materials.size() - 1, back.haptics.mesh_material.size());
  return cli::exit_ok;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("haptic_material", usage_text, argc, argv, [](cli::Parser& p) {
    Args a;
    cli::Input model("MODEL.gltf");
    while (p.next()) {
      if (p.is("--out"))
        a.out = p.output_file();
      else if (p.is("--info"))
        a.info = true;
      else if (p.is("--stiffness")) {
        a.pictures.stiffness = picture_flag(p, true, cli::open_closed(0.0, 1e6));
        a.any = true;
      } else if (p.is("--friction")) {
        a.pictures.friction = picture_flag(p, true, cli::closed(0.0, 10.0));
        a.any = true;
      } else if (p.is("--texture")) {
        a.pictures.texture = picture_flag(p, false, cli::closed(0.0, 100.0));
        a.any = true;
      } else if (p.is("--vibration")) {
        a.pictures.vibration_ids = load_image(p.value());
        a.any = true;
      } else if (p.is("--name"))
        a.pictures.name = p.value();
      else
        p.input_or_unknown(model);
    }
    a.model = model.required();
    if (a.info == !a.out.empty()) throw cli::UsageError("one of --out PATH or --info is required");
    if (!a.out.empty() && !a.any)
      throw cli::UsageError("--out needs at least one of --stiffness, --friction, --texture, --vibration");
    p.finish();
    return a.info ? info(a) : author(a);
  });
}

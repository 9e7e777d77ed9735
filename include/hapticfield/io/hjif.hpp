#pragma once
/// @file hjif.hpp
/// MPEG-I Haptics interchange files (.hjif, ISO/IEC 23090-31: JSON) into the
/// haptic media model (material/haptic_media.hpp) and back, through
/// nlohmann-json (target hapticfield::hjif). Never used in a tick.
///
/// Reading: every field the model holds is checked for its type; anything
/// else (avatars, syncs, reference devices, priorities, unknown fields) is
/// kept as raw JSON and written back unchanged; unknown band types, effect
/// types and Composite effects are skipped. Each kept or skipped field gives
/// one note (HjifFile::notes). A file that is not JSON, breaks a limit
/// (HjifLimits: bytes, nesting depth, values, array length, string length) or
/// has a wrong type gives one FileError naming the file and the JSON path.
///
/// Writing: the layout of the MPEG reference Encoder's files (every field its
/// loader requires, in its order), so the reference software reads them.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/material/haptic_media.hpp"

namespace hapticfield::io {

/// Bounds on what one .hjif may hold; each is named in the error it gives.
struct HjifLimits {
  std::uintmax_t max_bytes{std::uintmax_t{64} << 20};  ///< file size [bytes]
  std::size_t max_depth{32};                           ///< nesting of objects and arrays
  std::size_t max_values{8'000'000};                   ///< JSON values in the whole file
  std::size_t max_array{4'000'000};                    ///< elements of one array
  std::size_t max_string{1u << 20};                    ///< bytes of one string (wavelet blocks are a few kB)
};

/// A file read: the media and what was kept without rendering or skipped.
struct HjifFile {
  material::HapticMedia media;
  std::vector<std::string> notes;  ///< one line each, without repeats
};

namespace detail {

using Json = nlohmann::json;

/// Thrown from inside the parser's callback when a limit is passed.
struct HjifLimitHit {
  std::string what;
};

class HjifReader {
 public:
  HjifReader(std::string name, HjifLimits limits) : name_(std::move(name)), limits_(limits) {}

  HjifFile read(std::string_view text) {
    if (text.size() > limits_.max_bytes)
      fail("", std::to_string(text.size()) + " bytes, larger than the limit of " + std::to_string(limits_.max_bytes) +
                   " bytes");
    Json root;
    try {
      std::size_t values = 0;
      const auto cb = [&](int depth, Json::parse_event_t event, Json& parsed) -> bool {
        const auto d = static_cast<std::size_t>(depth);
        if ((event == Json::parse_event_t::object_start || event == Json::parse_event_t::array_start) &&
            d + 1 > limits_.max_depth)
          throw HjifLimitHit{"nested deeper than the limit of " + std::to_string(limits_.max_depth) + " levels"};
        if (event == Json::parse_event_t::value || event == Json::parse_event_t::object_end ||
            event == Json::parse_event_t::array_end) {
          if (++values > limits_.max_values)
            throw HjifLimitHit{"more than the limit of " + std::to_string(limits_.max_values) + " JSON values"};
          if (parsed.is_string() && parsed.get_ref<const std::string&>().size() > limits_.max_string)
            throw HjifLimitHit{"a string of " + std::to_string(parsed.get_ref<const std::string&>().size()) +
                               " bytes, longer than the limit of " + std::to_string(limits_.max_string) + " bytes"};
          if (parsed.is_array() && parsed.size() > limits_.max_array)
            throw HjifLimitHit{"an array of " + std::to_string(parsed.size()) + " elements, more than the limit of " +
                               std::to_string(limits_.max_array)};
        }
        return true;
      };
      root = Json::parse(text.begin(), text.end(), cb, /*allow_exceptions=*/true, /*ignore_comments=*/false);
    } catch (const HjifLimitHit& e) {
      fail("", e.what);
    } catch (const Json::exception& e) {
      std::string why = e.what();
      if (const auto p = why.find("] "); p != std::string::npos) why = why.substr(p + 2);
      fail("", "not JSON: " + why);
    }
    HjifFile out;
    read_media(root, out.media);
    out.notes.assign(notes_.begin(), notes_.end());
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& why) const {
    throw FileError(name_ + ": " + (path.empty() ? "" : path + ": ") + why);
  }
  void note(const std::string& n) {
    if (notes_.size() < 200) notes_.insert(n);
  }
  static const char* type_name(const Json& j) noexcept { return j.type_name(); }

  const Json& need(const Json& obj, const char* key, const std::string& path) const {
    const auto it = obj.find(key);
    if (it == obj.end()) fail(path, std::string("missing \"") + key + "\"");
    return *it;
  }
  void expect(bool ok, const Json& j, const std::string& path, const char* what) const {
    if (!ok) fail(path, std::string("expected ") + what + ", got " + type_name(j));
  }
  double number(const Json& j, const std::string& path) const {
    expect(j.is_number(), j, path, "a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(path, "not a finite number");
    return v;
  }
  std::int64_t integer(const Json& j, const std::string& path, std::int64_t lo, std::int64_t hi) const {
    expect(j.is_number_integer() || (j.is_number_float() && std::floor(j.get<double>()) == j.get<double>()), j, path,
           "an integer");
    double d = j.get<double>();
    if (j.is_number_unsigned()) d = static_cast<double>(j.get<std::uint64_t>());
    if (!(d >= static_cast<double>(lo) && d <= static_cast<double>(hi)))
      fail(path, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return j.is_number_float()
               ? static_cast<std::int64_t>(d)
               : (j.is_number_unsigned() ? static_cast<std::int64_t>(j.get<std::uint64_t>()) : j.get<std::int64_t>());
  }
  std::string string(const Json& j, const std::string& path) const {
    expect(j.is_string(), j, path, "a string");
    return j.get<std::string>();
  }
  const Json& array(const Json& j, const std::string& path) const {
    expect(j.is_array(), j, path, "an array");
    return j;
  }
  const Json& object(const Json& j, const std::string& path) const {
    expect(j.is_object(), j, path, "an object");
    return j;
  }
  /// Keeps every key of `obj` not in `known` as raw JSON, with a note naming where.
  void keep_rest(const Json& obj, std::initializer_list<std::string_view> known, material::ExtraFields& extra,
                 const char* level) {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      bool modelled = false;
      for (std::string_view k : known)
        modelled = modelled || it.key() == k;
      if (modelled) continue;
      extra.emplace_back(it.key(), it.value().dump());
      note(std::string("kept, not rendered: ") + level + "." + it.key());
    }
  }

  static constexpr std::int64_t max_ticks = std::int64_t{1} << 52;  // exact in a double

  void read_media(const Json& root, material::HapticMedia& m) {
    object(root, "(top level)");
    const auto opt_string = [&](const char* key, std::string& into) {
      if (const auto it = root.find(key); it != root.end()) {
        into = string(*it, key);
      } else {
        note(std::string("missing, written back with a default: ") + key);
      }
    };
    opt_string("version", m.version);
    opt_string("profile", m.profile);
    opt_string("date", m.date);
    opt_string("description", m.description);
    if (const auto it = root.find("level"); it != root.end()) m.level = integer(*it, "level", 0, 255);
    if (const auto it = root.find("timescale"); it != root.end())
      m.timescale = integer(*it, "timescale", 1, std::numeric_limits<std::uint32_t>::max());
    else
      note("missing \"timescale\": 1000 ticks per second");
    const Json& ps = array(need(root, "perceptions", ""), "perceptions");
    for (std::size_t i = 0; i < ps.size(); ++i) {
      material::Perception p;
      read_perception(ps[i], "perceptions[" + std::to_string(i) + "]", p);
      m.perceptions.push_back(std::move(p));
    }
    keep_rest(root, {"version", "profile", "level", "date", "description", "timescale", "perceptions"}, m.extra,
              "(top level)");
  }

  void read_perception(const Json& j, const std::string& path, material::Perception& p) {
    object(j, path);
    if (const auto it = j.find("id"); it != j.end()) p.id = integer(*it, path + ".id", INT32_MIN, INT32_MAX);
    if (const auto it = j.find("avatar_id"); it != j.end())
      p.avatar_id = integer(*it, path + ".avatar_id", INT32_MIN, INT32_MAX);
    if (const auto it = j.find("description"); it != j.end()) p.description = string(*it, path + ".description");
    if (const auto it = j.find("perception_modality"); it != j.end()) {
      p.modality = string(*it, path + ".perception_modality");
    } else {
      note("missing perception_modality: taken as \"Other\"");
    }
    if (material::modality_kind(p.modality) == material::ModalityKind::other && p.modality != "Other")
      note("modality \"" + p.modality.substr(0, 64) + "\": rendered as a signal, played on the vibration path");
    if (const auto it = j.find("perception_unit_exponent"); it != j.end()) {
      p.perception_unit_exponent = integer(*it, path + ".perception_unit_exponent", -128, 127);
      p.has_perception_unit_exponent = true;
    }
    if (const auto it = j.find("effect_library"); it != j.end()) {
      const Json& lib = array(*it, path + ".effect_library");
      for (std::size_t i = 0; i < lib.size(); ++i) {
        material::Effect e;
        if (read_effect(lib[i], path + ".effect_library[" + std::to_string(i) + "]", e))
          p.effect_library.push_back(std::move(e));
      }
    }
    const Json& cs = array(need(j, "channels", path), path + ".channels");
    for (std::size_t i = 0; i < cs.size(); ++i) {
      material::Channel c;
      read_channel(cs[i], path + ".channels[" + std::to_string(i) + "]", c);
      p.channels.push_back(std::move(c));
    }
    keep_rest(j,
              {"id", "avatar_id", "description", "perception_modality", "perception_unit_exponent", "effect_library",
               "channels"},
              p.extra, "perception");
  }

  void read_channel(const Json& j, const std::string& path, material::Channel& c) {
    object(j, path);
    if (const auto it = j.find("id"); it != j.end()) c.id = integer(*it, path + ".id", INT32_MIN, INT32_MAX);
    if (const auto it = j.find("description"); it != j.end()) c.description = string(*it, path + ".description");
    if (const auto it = j.find("gain"); it != j.end()) c.gain = number(*it, path + ".gain");
    if (const auto it = j.find("mixing_coefficient"); it != j.end())
      c.mixing_coefficient = number(*it, path + ".mixing_coefficient");
    else
      note("channel without mixing_coefficient: 1 written back");
    if (const auto it = j.find("body_part_mask"); it != j.end())
      c.body_part_mask = static_cast<std::uint32_t>(integer(*it, path + ".body_part_mask", 0, UINT32_MAX));
    if (const auto it = j.find("frequency_sampling"); it != j.end())
      c.frequency_sampling = integer(*it, path + ".frequency_sampling", 1, UINT32_MAX);
    if (const auto it = j.find("sample_count"); it != j.end())
      c.sample_count = integer(*it, path + ".sample_count", 0, UINT32_MAX);
    const Json& bs = array(need(j, "bands", path), path + ".bands");
    for (std::size_t i = 0; i < bs.size(); ++i) {
      material::Band b;
      if (read_band(bs[i], path + ".bands[" + std::to_string(i) + "]", b)) c.bands.push_back(std::move(b));
    }
    keep_rest(j,
              {"id", "description", "gain", "mixing_coefficient", "body_part_mask", "frequency_sampling",
               "sample_count", "bands"},
              c.extra, "channel");
  }

  bool read_band(const Json& j, const std::string& path, material::Band& b) {
    object(j, path);
    const std::string type = string(need(j, "band_type", path), path + ".band_type");
    if (type == "Transient")
      b.type = material::BandType::transient;
    else if (type == "Curve")
      b.type = material::BandType::curve;
    else if (type == "VectorialWave")
      b.type = material::BandType::vectorial_wave;
    else if (type == "WaveletWave")
      b.type = material::BandType::wavelet_wave;
    else {
      note("skipped: band of unknown band_type \"" + type.substr(0, 64) + "\"");
      return false;
    }
    if (const auto it = j.find("curve_type"); it != j.end()) {
      const std::string ct = string(*it, path + ".curve_type");
      b.has_curve_type = true;
      static constexpr std::pair<const char*, material::CurveType> names[] = {
          {"Unknown", material::CurveType::unknown}, {"Cubic", material::CurveType::cubic},
          {"Linear", material::CurveType::linear},   {"Akima", material::CurveType::akima},
          {"Bezier", material::CurveType::bezier},   {"Bspline", material::CurveType::bspline}};
      bool found = false;
      for (const auto& [n, t] : names)
        if (ct == n) b.curve_type = t, found = true;
      if (!found) note("curve_type \"" + ct.substr(0, 64) + "\" unknown: rendered as Unknown (cubic)");
    }
    if (const auto it = j.find("lower_frequency_limit"); it != j.end())
      b.lower_frequency_limit = number(*it, path + ".lower_frequency_limit");
    if (const auto it = j.find("upper_frequency_limit"); it != j.end())
      b.upper_frequency_limit = number(*it, path + ".upper_frequency_limit");
    if (const auto it = j.find("block_length"); it != j.end())
      b.block_length = integer(*it, path + ".block_length", 0, INT32_MAX);
    const Json& es = array(need(j, "effects", path), path + ".effects");
    for (std::size_t i = 0; i < es.size(); ++i) {
      material::Effect e;
      if (read_effect(es[i], path + ".effects[" + std::to_string(i) + "]", e)) b.effects.push_back(std::move(e));
    }
    keep_rest(j,
              {"band_type", "curve_type", "lower_frequency_limit", "upper_frequency_limit", "block_length", "effects"},
              b.extra, "band");
    return true;
  }

  bool read_effect(const Json& j, const std::string& path, material::Effect& e) {
    object(j, path);
    std::string type = "Basis";
    if (const auto it = j.find("effect_type"); it != j.end()) type = string(*it, path + ".effect_type");
    if (type == "Basis")
      e.type = material::EffectType::basis;
    else if (type == "Reference")
      e.type = material::EffectType::reference;
    else if (type == "Composite") {
      note("skipped: Composite effects (their timeline is not rendered)");
      return false;
    } else {
      note("skipped: effect of unknown effect_type \"" + type.substr(0, 64) + "\"");
      return false;
    }
    if (const auto it = j.find("id"); it != j.end()) e.id = integer(*it, path + ".id", INT32_MIN, INT32_MAX);
    if (e.type == material::EffectType::reference && e.id < 0) fail(path, "Reference effect without an \"id\"");
    if (const auto it = j.find("position"); it != j.end()) e.position = integer(*it, path + ".position", 0, max_ticks);
    if (const auto it = j.find("phase"); it != j.end()) e.phase = number(*it, path + ".phase");
    if (const auto it = j.find("base_signal"); it != j.end()) {
      const std::string s = string(*it, path + ".base_signal");
      static constexpr std::pair<const char*, material::BaseSignal> names[] = {
          {"Sine", material::BaseSignal::sine},
          {"Square", material::BaseSignal::square},
          {"Triangle", material::BaseSignal::triangle},
          {"SawToothUp", material::BaseSignal::saw_tooth_up},
          {"SawToothDown", material::BaseSignal::saw_tooth_down}};
      bool found = false;
      for (const auto& [n, t] : names)
        if (s == n) e.base_signal = t, found = true;
      if (!found) note("base_signal \"" + s.substr(0, 64) + "\" unknown: rendered as Sine");
    }
    if (const auto it = j.find("wavelet_stream"); it != j.end())
      e.wavelet_stream = string(*it, path + ".wavelet_stream");
    if (const auto it = j.find("keyframes"); it != j.end()) {
      const Json& ks = array(*it, path + ".keyframes");
      e.keyframes.reserve(ks.size());
      std::int64_t last = 0;
      bool sorted = true;
      for (std::size_t i = 0; i < ks.size(); ++i) {
        const std::string kp = path + ".keyframes[" + std::to_string(i) + "]";
        const Json& k = object(ks[i], kp);
        material::Keyframe kf;
        if (const auto r = k.find("relative_position"); r != k.end())
          kf.relative_position = integer(*r, kp + ".relative_position", 0, max_ticks);
        else
          kf.relative_position = last;  // the reference reads an absent position as the previous one's
        if (const auto a = k.find("amplitude_modulation"); a != k.end())
          kf.amplitude = number(*a, kp + ".amplitude_modulation");
        if (const auto f = k.find("frequency_modulation"); f != k.end()) {
          kf.frequency = number(*f, kp + ".frequency_modulation");
          if (*kf.frequency < 0.0) fail(kp + ".frequency_modulation", "negative frequency");
        }
        for (auto it2 = k.begin(); it2 != k.end(); ++it2)
          if (it2.key() != "relative_position" && it2.key() != "amplitude_modulation" &&
              it2.key() != "frequency_modulation")
            note("skipped: keyframe field \"" + it2.key().substr(0, 64) + "\"");
        sorted = sorted && *kf.relative_position >= last;
        last = *kf.relative_position;
        e.keyframes.push_back(kf);
      }
      if (!sorted) {
        note("keyframes out of order: sorted by relative_position");
        std::stable_sort(e.keyframes.begin(), e.keyframes.end(),
                         [](const auto& a, const auto& b) { return *a.relative_position < *b.relative_position; });
      }
    }
    keep_rest(j, {"effect_type", "id", "position", "phase", "base_signal", "wavelet_stream", "keyframes"}, e.extra,
              "effect");
    return true;
  }

  std::string name_;
  HjifLimits limits_;
  std::set<std::string> notes_;
};

using OrderedJson = nlohmann::ordered_json;

inline void put_extra(OrderedJson& j, const material::ExtraFields& extra) {
  for (const auto& [k, v] : extra)
    j[k] = OrderedJson::parse(v);
}
inline void put_number(OrderedJson& j, const char* key, double v) {
  if (std::floor(v) == v && std::abs(v) < 9.0e15)
    j[key] = static_cast<std::int64_t>(v);
  else
    j[key] = v;
}

inline OrderedJson effect_json(const material::Effect& e, material::BandType band, bool library) {
  OrderedJson j;
  j["effect_type"] = material::effect_type_name(e.type);
  if (library || e.type == material::EffectType::reference) j["id"] = e.id;
  j["position"] = e.position;
  if (e.type == material::EffectType::reference) {
    put_extra(j, e.extra);
    return j;
  }
  if (band == material::BandType::vectorial_wave || library) {
    j["phase"] = e.phase;
    j["base_signal"] = material::base_signal_name(e.base_signal);
  }
  const bool wavelet = band == material::BandType::wavelet_wave && !library;
  if (wavelet) j["wavelet_stream"] = e.wavelet_stream;
  if (!wavelet || !e.keyframes.empty()) {  // older drafts held wavelet data as keyframes: kept
    OrderedJson ks = OrderedJson::array();
    for (const material::Keyframe& k : e.keyframes) {
      OrderedJson kj;
      if (k.relative_position) kj["relative_position"] = *k.relative_position;
      if (k.amplitude) kj["amplitude_modulation"] = *k.amplitude;
      if (k.frequency) put_number(kj, "frequency_modulation", *k.frequency);
      ks.push_back(std::move(kj));
    }
    j["keyframes"] = std::move(ks);
  }
  put_extra(j, e.extra);
  return j;
}

}  // namespace detail

/// Reads .hjif text already in memory; `name` is used in errors.
/// @throws FileError "<name>: <json path>: <reason>" for text that is not
///         JSON, a limit passed, a missing required member or a wrong type.
[[nodiscard]] inline HjifFile parse_hjif(std::string_view text, const std::string& name = "hjif",
                                         HjifLimits limits = {}) {
  return detail::HjifReader(name, limits).read(text);
}

/// Reads a .hjif file.
/// @throws FileError as parse_hjif, or when the file is missing, unreadable
///         or larger than limits.max_bytes.
[[nodiscard]] inline HjifFile load_hjif(const std::string& path, HjifLimits limits = {}) {
  check_file(path, limits.max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open '" + path + "'");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_hjif(text, path, limits);
}

/// The media as .hjif text, laid out as the MPEG reference Encoder writes
/// it (its loader requires every top-level, perception and channel field
/// written here). Kept fields come back under their keys.
[[nodiscard]] inline std::string write_hjif_string(const material::HapticMedia& m) {
  using detail::OrderedJson;
  OrderedJson root;
  root["version"] = m.version;
  root["profile"] = m.profile;
  root["level"] = m.level;
  root["date"] = m.date;
  root["description"] = m.description;
  root["timescale"] = m.timescale;
  root["avatars"] = OrderedJson::array();
  OrderedJson ps = OrderedJson::array();
  for (const material::Perception& p : m.perceptions) {
    OrderedJson pj;
    pj["id"] = p.id;
    pj["avatar_id"] = p.avatar_id;
    pj["description"] = p.description;
    pj["perception_modality"] = p.modality;
    if (p.has_perception_unit_exponent) pj["perception_unit_exponent"] = p.perception_unit_exponent;
    pj["reference_devices"] = OrderedJson::array();
    OrderedJson lib = OrderedJson::array();
    for (const material::Effect& e : p.effect_library)
      lib.push_back(detail::effect_json(e, material::BandType::vectorial_wave, true));
    pj["effect_library"] = std::move(lib);
    OrderedJson cs = OrderedJson::array();
    for (const material::Channel& c : p.channels) {
      OrderedJson cj;
      cj["id"] = c.id;
      cj["description"] = c.description;
      cj["gain"] = c.gain;
      cj["mixing_coefficient"] = c.mixing_coefficient;
      cj["body_part_mask"] = c.body_part_mask;
      if (c.frequency_sampling) cj["frequency_sampling"] = *c.frequency_sampling;
      if (c.sample_count) cj["sample_count"] = *c.sample_count;
      OrderedJson bs = OrderedJson::array();
      for (const material::Band& b : c.bands) {
        OrderedJson bj;
        bj["band_type"] = material::band_type_name(b.type);
        if (b.type == material::BandType::curve || b.has_curve_type)
          bj["curve_type"] = material::curve_type_name(b.curve_type);
        if (b.type == material::BandType::wavelet_wave) bj["block_length"] = b.block_length.value_or(0);
        detail::put_number(bj, "lower_frequency_limit", b.lower_frequency_limit);
        detail::put_number(bj, "upper_frequency_limit", b.upper_frequency_limit);
        OrderedJson es = OrderedJson::array();
        for (const material::Effect& e : b.effects)
          es.push_back(detail::effect_json(e, b.type, false));
        bj["effects"] = std::move(es);
        detail::put_extra(bj, b.extra);
        bs.push_back(std::move(bj));
      }
      cj["bands"] = std::move(bs);
      detail::put_extra(cj, c.extra);
      cs.push_back(std::move(cj));
    }
    pj["channels"] = std::move(cs);
    // reference_devices from the file replaces the empty default above
    detail::put_extra(pj, p.extra);
    ps.push_back(std::move(pj));
  }
  root["perceptions"] = std::move(ps);
  root["syncs"] = OrderedJson::array();
  detail::put_extra(root, m.extra);
  return root.dump();
}

/// Writes the media to a .hjif file.
/// @throws FileError when the file cannot be written.
inline void save_hjif(const material::HapticMedia& m, const std::string& path) {
  const std::string text = write_hjif_string(m);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError("cannot write '" + path + "'");
  out << text;
  out.flush();
  if (!out) throw FileError("cannot write '" + path + "': write failed");
}

}  // namespace hapticfield::io

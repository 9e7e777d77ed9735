#pragma once
/// @file hatt_model_file.hpp
/// Reads Penn Haptic Texture Toolkit (HaTT) modelSet files (Culbertson,
/// Lopez Delgado & Kuchenbecker, IEEE Haptics Symposium 2014) into a
/// HattModelSet. XML is parsed by pugixml (link hapticfield::hatt); this is
/// setup code, never called on the servo path.
///
/// Hostile files are bounded before any work that grows faster than the
/// file: sizes are checked against their declared counts before numbers are
/// converted, orders are capped at max_hatt_order, and the AR -> LSF
/// conversion (only for models without <ARlsf>) has a work budget, so a file
/// of at most 1 MB loads or fails in well under a second.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <pugixml.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/lsf.hpp"

namespace hapticfield::texture {

/// A modelSet file that is malformed: what() names the file and the field.
class HattFileError : public FileError {
 public:
  using FileError::FileError;
};

/// Largest modelSet file read [bytes] (the toolkit's are below 1 MB).
inline constexpr std::uintmax_t max_hatt_file_bytes = std::uintmax_t{16} << 20;
/// Largest AR or MA order (<numARCoeff>, <numMACoeff>) accepted.
inline constexpr std::size_t max_hatt_order = 256;
/// Most models (<numMod>) and triangles (<numTri>) in one set.
inline constexpr std::size_t max_hatt_models = 4096;
inline constexpr std::size_t max_hatt_triangles = 2 * max_hatt_models;
/// Range of <SampleRate> accepted [Hz]. The toolkit's models are 10 kHz and
/// its resampled sets 1 kHz; a rate outside 100 Hz..100 kHz is no texture
/// recording's, and a huge one would make the audio path run millions of
/// model steps a second (vibration/hatt_source.hpp caps them as well).
inline constexpr double min_hatt_sample_rate = 100.0;
inline constexpr double max_hatt_sample_rate = 100000.0;
/// Budget for converting <ARcoeff> to LSFs in one file: the sum over the
/// converted models of (p + 1)^2 (about 2 us each, so at most ~0.2 s).
inline constexpr std::size_t max_hatt_conversion_work = 100000;

namespace detail {

/// Concatenates strings by appending (avoids a g++ 12 -Wrestrict false
/// positive on `"literal" + std::string(...)`).
template <class... Parts>
[[nodiscard]] std::string cat(const Parts&... parts) {
  std::string s;
  (s.append(std::string_view(parts)), ...);
  return s;
}

[[noreturn]] inline void hatt_fail(std::string_view source, const std::string& what) {
  throw HattFileError(cat("HaTT model set", source.empty() ? "" : " '", source, source.empty() ? "" : "'", ": ", what));
}

inline std::string_view hatt_trim(std::string_view t) noexcept {
  const auto space = [](char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; };
  while (!t.empty() && space(t.front()))
    t.remove_prefix(1);
  while (!t.empty() && space(t.back()))
    t.remove_suffix(1);
  return t;
}

/// A quoted excerpt of at most 40 characters for messages.
inline std::string hatt_excerpt(std::string_view t) {
  return t.size() <= 40 ? std::string(t) : cat(t.substr(0, 40), "...");
}

inline double hatt_number_text(std::string_view text, std::string_view source, const std::string& field) {
  std::string_view t = hatt_trim(text);
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
    hatt_fail(source, cat(field, " is not a finite number: '", hatt_excerpt(hatt_trim(text)), "'"));
  return v;
}

inline double hatt_number(const pugi::xml_node& node, std::string_view source, const std::string& field) {
  return hatt_number_text(node.text().get(), source, field);
}

inline pugi::xml_node hatt_required(const pugi::xml_node& parent, const char* name, std::string_view source,
                                    std::string_view where = {}) {
  const pugi::xml_node n = parent.child(name);
  if (!n) hatt_fail(source, cat(where, where.empty() ? "" : ": ", "missing <", name, "> in <", parent.name(), ">"));
  return n;
}

/// The child spelled as the toolkit writes it (<SampleRate>) or in lower
/// case (<sampleRate>); both at once is an error. Null when absent.
inline pugi::xml_node hatt_either(const pugi::xml_node& parent, const char* toolkit, const char* lower,
                                  std::string_view source) {
  const pugi::xml_node a = parent.child(toolkit);
  const pugi::xml_node b = parent.child(lower);
  if (a && b) hatt_fail(source, cat("both <", toolkit, "> and <", lower, ">: keep one"));
  return a ? a : b;
}

inline std::size_t hatt_count(const pugi::xml_node& parent, const char* name, std::string_view source,
                              std::size_t max) {
  const double v = hatt_number(hatt_required(parent, name, source), source, cat("<", name, ">"));
  if (v < 0.0 || v != std::floor(v) || v > static_cast<double>(max))
    hatt_fail(source, cat("<", name, "> must be an integer in 0..", std::to_string(max), ", not ",
                          hatt_excerpt(hatt_trim(parent.child(name).text().get()))));
  return static_cast<std::size_t>(v);
}

/// Number of entries of a list: its <value> children (the HaTT convention),
/// else the whitespace-separated tokens of its text. Counting is linear in
/// the list and converts nothing.
inline std::size_t hatt_list_size(const pugi::xml_node& list) {
  std::size_t n = 0;
  for (pugi::xml_node v = list.child("value"); v; v = v.next_sibling("value"))
    ++n;
  if (n > 0) return n;
  std::string_view t = list.text().get();
  bool in_token = false;
  for (char c : t) {
    const bool space = c == ' ' || c == '\n' || c == '\r' || c == '\t';
    if (!space && !in_token) ++n;
    in_token = !space;
  }
  return n;
}

/// The values of a list whose size the caller has checked.
inline std::vector<double> hatt_list(const pugi::xml_node& list, std::string_view source, std::string_view where = {}) {
  std::vector<double> out;
  const std::string field = cat(where, where.empty() ? "" : ": ", "<", list.name(), ">");
  if (list.child("value")) {
    for (pugi::xml_node v = list.child("value"); v; v = v.next_sibling("value"))
      out.push_back(hatt_number(v, source, cat(field, "<value>")));
    return out;
  }
  std::string_view t = list.text().get();
  std::size_t i = 0;
  while (i < t.size()) {
    while (i < t.size() && (t[i] == ' ' || t[i] == '\n' || t[i] == '\r' || t[i] == '\t'))
      ++i;
    std::size_t j = i;
    while (j < t.size() && !(t[j] == ' ' || t[j] == '\n' || t[j] == '\r' || t[j] == '\t'))
      ++j;
    if (j > i) out.push_back(hatt_number_text(t.substr(i, j - i), source, field));
    i = j;
  }
  return out;
}

/// A list that must hold exactly `n` values (checked before converting).
inline std::vector<double> hatt_list_of(const pugi::xml_node& list, std::size_t n, std::string_view source,
                                        std::string_view where, std::string_view count_name) {
  const std::size_t size = hatt_list_size(list);
  if (size != n)
    hatt_fail(source, cat(where, where.empty() ? "" : ": ", "<", list.name(), "> holds ", std::to_string(size),
                          " values, ", count_name, " = ", std::to_string(n)));
  return hatt_list(list, source, where);
}

inline void hatt_check_lsf(const std::vector<double>& lsf, std::string_view source, const std::string& what) {
  for (std::size_t i = 0; i < lsf.size(); ++i)
    if (!(lsf[i] > 0.0 && lsf[i] < std::numbers::pi) || (i > 0 && !(lsf[i] > lsf[i - 1])))
      hatt_fail(source, what + " must increase strictly within (0, pi) [rad]");
}

inline std::string hatt_units(const pugi::xml_node& n) {
  return std::string(hatt_trim(n.text().get()));
}

}  // namespace detail

/// Parses a modelSet document held in memory; `source` names it in messages.
///
/// Required: <modelSet> with <mu>, <numMod>, <numTri>, <speedList>,
/// <forceList>, <tri> x numTri (three vertex indices each, 1-based as written
/// by MATLAB, or 0-based when an index 0 occurs), <numARCoeff>, and numMod
/// <model> elements each with <ARlsf> (or <ARcoeff>), <var>, <speedMod>,
/// <forceMod>, plus <MAlsf> and <gain> when numMACoeff > 0.
/// Optional: <numMACoeff> (default 0), <maxSpeed>, <maxForce>, <htmlName> or
/// <material>, <ARcoeff>, <MAcoeff> (p or p + 1 values, a_0 = 1 first), and,
/// spelled as the toolkit writes them or in lower case:
/// <SampleRate> [Hz] (default 10000; the toolkit's resampled sets say 1000;
/// min_hatt_sample_rate..max_hatt_sample_rate, 100 Hz..100 kHz),
/// <SpeedUnits> ("mm/s" default or "m/s"), <AccelUnits> ("m/s^2" default or
/// "g"), <ForceUnits> ("N").
/// @throws HattFileError (a FileError) naming the source and the field for
///         malformed XML, missing or non-numeric fields, counts that do not
///         match or exceed the caps, indices out of range, degenerate
///         triangles, LSFs not increasing in (0, pi), a negative variance,
///         a <SampleRate> outside 100 Hz..100 kHz,
///         or too much <ARcoeff> conversion work.
[[nodiscard]] inline HattModelSet parse_hatt_model_set(std::string_view text, std::string_view source = {}) {
  using namespace detail;
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed_xml =
      doc.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (parsed_xml.status == pugi::status_no_document_element) hatt_fail(source, "no root element, expected <modelSet>");
  if (!parsed_xml)
    hatt_fail(source,
              cat("malformed XML: ", parsed_xml.description(), " (at byte ", std::to_string(parsed_xml.offset), ")"));
  pugi::xml_node root;
  for (pugi::xml_node n = doc.first_child(); n; n = n.next_sibling()) {
    if (n.type() != pugi::node_element) continue;
    if (root) hatt_fail(source, cat("element <", n.name(), "> after the root element"));
    root = n;
  }
  if (!root) hatt_fail(source, "no root element, expected <modelSet>");
  if (std::string_view(root.name()) != "modelSet")
    hatt_fail(source, cat("root element is <", root.name(), ">, expected <modelSet>"));

  HattModelSet set;
  set.name = std::string(source);
  if (const auto n = root.child("htmlName"))
    set.name = std::string(hatt_trim(n.text().get()));
  else if (const auto m = root.child("material"))
    set.name = std::string(hatt_trim(m.text().get()));
  set.mu = hatt_number(hatt_required(root, "mu", source), source, "<mu>");
  if (set.mu < 0.0) hatt_fail(source, "<mu> must be >= 0");
  const std::size_t num_mod = hatt_count(root, "numMod", source, max_hatt_models);
  const std::size_t num_tri = hatt_count(root, "numTri", source, max_hatt_triangles);
  if (num_mod < 1) hatt_fail(source, "<numMod> must be >= 1");
  set.ar_order = hatt_count(root, "numARCoeff", source, max_hatt_order);
  set.ma_order = root.child("numMACoeff") ? hatt_count(root, "numMACoeff", source, max_hatt_order) : 0;
  if (set.ar_order < 1) hatt_fail(source, "<numARCoeff> must be >= 1");
  if (const auto n = hatt_either(root, "SampleRate", "sampleRate", source)) {
    set.sample_rate = hatt_number(n, source, cat("<", n.name(), ">"));
    if (!(set.sample_rate >= min_hatt_sample_rate && set.sample_rate <= max_hatt_sample_rate))
      hatt_fail(source, cat("<", n.name(), "> ", hatt_excerpt(hatt_trim(n.text().get())), " Hz is outside ",
                            std::to_string(static_cast<long>(min_hatt_sample_rate)), "..",
                            std::to_string(static_cast<long>(max_hatt_sample_rate)),
                            " Hz, the rates a HaTT model is recorded at (the toolkit's: 1000 and 10000)"));
  }
  if (const auto n = hatt_either(root, "SpeedUnits", "speedUnits", source)) {
    const std::string u = hatt_units(n);
    if (u == "mm/s")
      set.speed_to_file = 1000.0;
    else if (u == "m/s")
      set.speed_to_file = 1.0;
    else
      hatt_fail(source, cat("<", n.name(), "> must be mm/s or m/s, not '", hatt_excerpt(u), "'"));
  }
  if (const auto n = hatt_either(root, "AccelUnits", "accelUnits", source)) {
    const std::string u = hatt_units(n);
    if (u == "m/s^2")
      set.acceleration_to_si = 1.0;
    else if (u == "g")
      set.acceleration_to_si = 9.80665;
    else
      hatt_fail(source, cat("<", n.name(), "> must be m/s^2 or g, not '", hatt_excerpt(u), "'"));
  }
  if (const auto n = hatt_either(root, "ForceUnits", "forceUnits", source)) {
    if (hatt_units(n) != "N")
      hatt_fail(source, cat("<", n.name(), "> must be N, not '", hatt_excerpt(hatt_units(n)), "'"));
  }
  set.speeds = hatt_list_of(hatt_required(root, "speedList", source), num_mod, source, {}, "numMod");
  set.forces = hatt_list_of(hatt_required(root, "forceList", source), num_mod, source, {}, "numMod");
  double max_s = 0, max_f = 0;
  for (std::size_t i = 0; i < num_mod; ++i)
    max_s = std::max(max_s, set.speeds[i]), max_f = std::max(max_f, set.forces[i]);
  set.max_speed = root.child("maxSpeed") ? hatt_number(root.child("maxSpeed"), source, "<maxSpeed>") : max_s;
  set.max_force = root.child("maxForce") ? hatt_number(root.child("maxForce"), source, "<maxForce>") : max_f;

  // --- triangles: count first, then convert
  std::size_t tri_count = 0;
  for (auto t = root.child("tri"); t; t = t.next_sibling("tri"))
    ++tri_count;
  if (tri_count != num_tri)
    hatt_fail(source, cat("found ", std::to_string(tri_count), " <tri>, <numTri> says ", std::to_string(num_tri)));
  if (num_mod >= 3 && num_tri < 1) hatt_fail(source, cat("no <tri> for ", std::to_string(num_mod), " models"));
  std::vector<std::array<double, 3>> raw;
  raw.reserve(num_tri);
  double min_index = std::numeric_limits<double>::infinity();
  std::size_t k_tri = 0;
  for (auto t = root.child("tri"); t; t = t.next_sibling("tri")) {
    const std::string where = cat("<tri> ", std::to_string(++k_tri));
    if (hatt_list_size(t) != 3) hatt_fail(source, where + ": each <tri> must hold three vertex indices");
    const std::vector<double> v = hatt_list(t, source, where);
    for (double x : v) {
      if (x != std::floor(x)) hatt_fail(source, where + ": <tri> indices must be integers");
      min_index = std::min(min_index, x);
    }
    raw.push_back({v[0], v[1], v[2]});
  }
  const double base = min_index == 0.0 ? 0.0 : 1.0;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    std::array<int, 3> t{};
    for (std::size_t k = 0; k < 3; ++k) {
      const double idx = raw[i][k] - base;
      if (idx < 0.0 || idx >= static_cast<double>(num_mod))
        hatt_fail(source, cat("<tri> ", std::to_string(i + 1), ": vertex index out of range"));
      t[k] = static_cast<int>(idx);
    }
    const auto s = [&](int v) { return set.speeds[static_cast<std::size_t>(v)]; };
    const auto f = [&](int v) { return set.forces[static_cast<std::size_t>(v)]; };
    const double ax = s(t[1]) - s(t[0]), ay = f(t[1]) - f(t[0]);
    const double bx = s(t[2]) - s(t[0]), by = f(t[2]) - f(t[0]);
    const double det = ax * by - ay * bx;
    if (!std::isfinite(det) || std::fabs(det) <= 1e-12 * (std::fabs(ax * by) + std::fabs(ay * bx) + 1e-300))
      hatt_fail(source,
                cat("<tri> ", std::to_string(i + 1), ": degenerate (its vertices are collinear or too far apart)"));
    set.triangles.push_back(t);
  }

  // --- models: count first, then convert each list after checking its size
  std::size_t model_count = 0;
  for (auto m = root.child("model"); m; m = m.next_sibling("model"))
    ++model_count;
  if (model_count != num_mod)
    hatt_fail(source, cat("found ", std::to_string(model_count), " <model>, <numMod> says ", std::to_string(num_mod)));
  std::vector<HattModel> parsed;
  parsed.reserve(num_mod);
  std::size_t conversion_work = 0;
  std::vector<double> last_coeff, last_lsf;  // the toolkit repeats models: convert each distinct list once
  std::size_t i_model = 0;
  for (auto m = root.child("model"); m; m = m.next_sibling("model")) {
    const std::string where = cat("<model> ", std::to_string(++i_model));
    HattModel h;
    h.speed = hatt_number(hatt_required(m, "speedMod", source, where), source, where + ": <speedMod>");
    h.force = hatt_number(hatt_required(m, "forceMod", source, where), source, where + ": <forceMod>");
    h.variance = hatt_number(hatt_required(m, "var", source, where), source, where + ": <var>");
    if (h.variance < 0.0) hatt_fail(source, where + ": <var> must be >= 0 (negative variance)");
    const auto read_coeff = [&](const pugi::xml_node& n, std::size_t order, const char* count_name) {
      const std::size_t size = hatt_list_size(n);
      if (size != order && size != order + 1)
        hatt_fail(source, cat(where, ": <", n.name(), "> holds ", std::to_string(size), " values, ", count_name, " = ",
                              std::to_string(order), " (expected ", std::to_string(order), " or ",
                              std::to_string(order + 1), ")"));
      return hatt_list(n, source, where);
    };
    if (const auto n = m.child("ARcoeff")) h.ar_coeff = read_coeff(n, set.ar_order, "numARCoeff");
    if (const auto n = m.child("MAcoeff")) h.ma_coeff = read_coeff(n, set.ma_order, "numMACoeff");
    if (const auto n = m.child("ARlsf")) {
      h.ar_lsf = hatt_list_of(n, set.ar_order, source, where, "numARCoeff");
    } else if (!h.ar_coeff.empty()) {
      std::vector<double> a = h.ar_coeff;
      if (a.size() == set.ar_order) a.insert(a.begin(), 1.0);
      if (a[0] != 1.0) hatt_fail(source, where + ": <ARcoeff> with numARCoeff + 1 values must start with 1");
      if (a == last_coeff) {
        h.ar_lsf = last_lsf;
      } else {
        conversion_work += (set.ar_order + 1) * (set.ar_order + 1);
        if (conversion_work > max_hatt_conversion_work)
          hatt_fail(source, cat(where, ": too many <ARcoeff> lists to convert to LSFs (give <ARlsf>; budget ",
                                std::to_string(max_hatt_conversion_work), " = sum of (numARCoeff + 1)^2)"));
        try {
          h.ar_lsf = ar_to_lsf(a);
        } catch (const std::invalid_argument& e) {
          hatt_fail(source, cat(where, ": <ARcoeff>: ", e.what()));
        }
        last_coeff = std::move(a);
        last_lsf = h.ar_lsf;
      }
    } else {
      hatt_fail(source, where + ": missing <ARlsf> (or <ARcoeff>)");
    }
    hatt_check_lsf(h.ar_lsf, source, where + ": <ARlsf>");
    if (set.ma_order > 0) {
      h.ma_lsf = hatt_list_of(hatt_required(m, "MAlsf", source, where), set.ma_order, source, where, "numMACoeff");
      hatt_check_lsf(h.ma_lsf, source, where + ": <MAlsf>");
      h.gain = hatt_number(hatt_required(m, "gain", source, where), source, where + ": <gain>");
    } else if (const auto g = m.child("gain")) {
      h.gain = hatt_number(g, source, where + ": <gain>");
    }
    parsed.push_back(std::move(h));
  }
  // order the models like the vertex lists: match <speedMod>/<forceMod> to
  // the list values (relative 1e-6), else keep the file's order; at most
  // max_hatt_models^2 comparisons, and one per model for files in order
  set.models.resize(num_mod);
  std::vector<bool> used(num_mod, false);
  for (std::size_t v = 0; v < num_mod; ++v) {
    std::size_t found = num_mod;
    for (std::size_t k = 0; k < num_mod && found == num_mod; ++k) {
      const std::size_t j = (v + k) % num_mod;  // usually j == v
      if (!used[j] && std::fabs(parsed[j].speed - set.speeds[v]) <= 1e-6 * (1.0 + std::fabs(set.speeds[v])) &&
          std::fabs(parsed[j].force - set.forces[v]) <= 1e-6 * (1.0 + std::fabs(set.forces[v])))
        found = j;
    }
    if (found == num_mod && !used[v])
      found = v;  // no value match: the file's order (the toolkit writes both in the same order)
    if (found == num_mod) hatt_fail(source, cat("no <model> for vertex ", std::to_string(v + 1), " of the lists"));
    used[found] = true;
    set.models[v] = parsed[found];
  }
  return set;
}

/// Reads and parses a modelSet file; the set's name defaults to the file's stem.
/// @throws FileError for a missing, unreadable or too large file (as every
///         component, see core/error.hpp), HattFileError for a malformed one.
[[nodiscard]] inline HattModelSet load_hatt_model_set(const std::filesystem::path& path) {
  const std::string text = read_file(path.string(), max_hatt_file_bytes);
  HattModelSet set = parse_hatt_model_set(text, path.string());
  if (set.name == path.string()) set.name = path.stem().string();
  return set;
}

/// The modelSet files (*.xml, sorted) in a directory such as HaTT's XML/.
/// @throws FileError when the directory does not exist or cannot be listed.
[[nodiscard]] inline std::vector<std::filesystem::path> hatt_model_files(const std::filesystem::path& dir) {
  std::error_code ec;
  const auto st = std::filesystem::status(dir, ec);
  if (!std::filesystem::exists(st)) throw FileError(detail::cat("cannot open '", dir.string(), "': no such directory"));
  if (!std::filesystem::is_directory(st))
    throw FileError(detail::cat("cannot open '", dir.string(), "': not a directory"));
  std::vector<std::filesystem::path> files;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    if (it->is_regular_file(e2) && it->path().extension() == ".xml") files.push_back(it->path());
  }
  if (ec) throw FileError(detail::cat("cannot list '", dir.string(), "': ", ec.message()));
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace hapticfield::texture

#pragma once
/// @file hatt.hpp
/// Data-driven texture models in the Penn Haptic Texture Toolkit format
/// (Culbertson, Lopez Delgado & Kuchenbecker, "One hundred data-driven haptic
/// texture models and open-source methods for rendering on 3D objects",
/// IEEE Haptics Symposium 2014).
///
/// A modelSet holds, for one material, AR (optionally ARMA) models of the
/// stylus acceleration recorded at a set of (tangential speed, normal force)
/// points, and a Delaunay triangulation of those points. Each tick the
/// renderer locates the current (speed, force) in the triangulation,
/// interpolates the models' line spectral frequencies (LSFs) and variance
/// barycentrically (interpolated LSFs stay sorted, so the AR filter stays
/// stable), converts the LSFs to AR coefficients, drives the filter with
/// Gaussian noise of that variance and turns the acceleration into a force
/// through an effective mass; Coulomb friction mu |Fc| opposes the motion.
///
/// The toolkit's files cannot ship with this project (their licence forbids
/// redistribution); see docs/textures.md for where to get them.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/arma.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/texture/xml.hpp"

namespace hapticfield::texture {

// --- line spectral frequencies ------------------------------------------------

namespace detail {
/// poly *= (1 + c1 z^-1 + c2 z^-2) in place; n = number of coefficients (grows by 2).
template <std::size_t N>
constexpr void multiply_quadratic(std::array<double, N>& poly, std::size_t& n, double c1, double c2 = 1.0) noexcept {
  for (std::size_t k = n + 2; k-- > 0;) {
    double v = k < n ? poly[k] : 0.0;
    if (k >= 1 && k - 1 < n) v += c1 * poly[k - 1];
    if (k >= 2 && k - 2 < n) v += c2 * poly[k - 2];
    poly[k] = v;
  }
  n += 2;
}
/// poly *= (1 + s z^-1) in place.
template <std::size_t N>
constexpr void multiply_linear(std::array<double, N>& poly, std::size_t& n, double s) noexcept {
  for (std::size_t k = n + 1; k-- > 0;) {
    double v = k < n ? poly[k] : 0.0;
    if (k >= 1) v += s * poly[k - 1];
    poly[k] = v;
  }
  n += 1;
}
}  // namespace detail

/// LSFs w_1 < ... < w_p in (0, pi) [rad] -> AR polynomial a_0 = 1, a_1..a_p
/// of A(z) = 1 + a_1 z^-1 + ... + a_p z^-p (Kondoz, "Digital Speech", ch. 4;
/// the same construction as MATLAB's lsf2poly): the odd-numbered LSFs are
/// the roots of the sum polynomial, the even-numbered ones of the difference
/// polynomial, A = (P + Q) / 2. noexcept and allocation-free; returns false
/// when p is 0 or above MaxOrder or when `a` has fewer than p + 1 entries.
template <std::size_t MaxOrder>
[[nodiscard]] bool lsf_to_ar(std::span<const double> lsf, std::span<double> a) noexcept {
  const std::size_t p = lsf.size();
  if (p == 0 || p > MaxOrder || a.size() < p + 1) return false;
  std::array<double, MaxOrder + 4> sum{}, diff{};
  std::size_t ns = 1, nd = 1;
  sum[0] = diff[0] = 1.0;
  for (std::size_t i = 0; i < p; ++i) {
    const double c = -2.0 * std::cos(lsf[i]);
    if (i % 2 == 0) detail::multiply_quadratic(sum, ns, c);
    else detail::multiply_quadratic(diff, nd, c);
  }
  if (p % 2 == 1) {
    // odd order: z = 1 and z = -1 are both roots of the difference polynomial
    detail::multiply_quadratic(diff, nd, 0.0, -1.0);  // (1 - z^-2)
  } else {
    detail::multiply_linear(diff, nd, -1.0);  // root z = 1
    detail::multiply_linear(sum, ns, 1.0);    // root z = -1
  }
  for (std::size_t k = 0; k <= p; ++k) a[k] = 0.5 * (sum[k] + diff[k]);
  return true;
}

/// Allocating convenience form (setup): returns a_0 = 1, a_1..a_p.
/// @throws std::invalid_argument for LSFs that are not strictly increasing
///         in (0, pi) or an order above 256.
[[nodiscard]] inline std::vector<double> lsf_to_ar(std::span<const double> lsf) {
  if (lsf.empty() || lsf.size() > 256) throw std::invalid_argument("lsf_to_ar: order must be in 1..256");
  for (std::size_t i = 0; i < lsf.size(); ++i)
    if (!(lsf[i] > 0.0 && lsf[i] < std::numbers::pi) || (i > 0 && !(lsf[i] > lsf[i - 1])))
      throw std::invalid_argument("lsf_to_ar: LSFs must increase strictly within (0, pi) [rad]");
  std::vector<double> a(lsf.size() + 1);
  (void)lsf_to_ar<256>(lsf, a);
  return a;
}

/// AR polynomial a_0 = 1, a_1..a_p (minimum phase) -> its p LSFs [rad], the
/// zeros on the unit circle of the sum and difference polynomials
/// A(z) +- z^-(p+1) A(1/z), found by a sign scan and bisection.
/// @throws std::invalid_argument when a_0 != 1, a coefficient is not
///         finite, or A is not minimum phase (its LSFs do not interlace).
[[nodiscard]] inline std::vector<double> ar_to_lsf(std::span<const double> a) {
  if (a.size() < 2 || a[0] != 1.0) throw std::invalid_argument("ar_to_lsf: need a_0 = 1 and order >= 1");
  if (!is_stable(a.subspan(1))) throw std::invalid_argument("ar_to_lsf: AR polynomial is not minimum phase");
  const std::size_t p = a.size() - 1;
  const auto coeff = [&](std::size_t k) { return k <= p ? a[k] : 0.0; };
  const double half = (p + 1) / 2.0;
  // e^{j w (p+1)/2} S(e^{jw}) = sum s_k cos(w (k - (p+1)/2)), s_k symmetric;
  // e^{j w (p+1)/2} D(e^{jw}) = -j sum d_k sin(w (k - (p+1)/2)), d_k antisymmetric
  const auto fs = [&](double w) {
    double v = 0;
    for (std::size_t k = 0; k <= p + 1; ++k) v += (coeff(k) + coeff(p + 1 - k)) * std::cos(w * (k - half));
    return v;
  };
  const auto fd = [&](double w) {
    double v = 0;
    for (std::size_t k = 0; k <= p + 1; ++k) v += (coeff(k) - coeff(p + 1 - k)) * std::sin(w * (k - half));
    return v;
  };
  std::vector<double> roots;
  const std::size_t grid = 256 * (p + 1);
  const double lo = 1e-7, hi = std::numbers::pi - 1e-7;
  const auto scan = [&](const auto& f) {
    double w0 = lo, f0 = f(w0);
    for (std::size_t i = 1; i <= grid; ++i) {
      const double w1 = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(grid);
      const double f1 = f(w1);
      if ((f0 < 0.0) != (f1 < 0.0)) {
        double a0 = w0, a1 = w1, fa = f0;
        for (int it = 0; it < 60; ++it) {
          const double m = 0.5 * (a0 + a1);
          const double fm = f(m);
          if ((fa < 0.0) == (fm < 0.0)) a0 = m, fa = fm;
          else a1 = m;
        }
        roots.push_back(0.5 * (a0 + a1));
      }
      w0 = w1;
      f0 = f1;
    }
  };
  scan(fs);
  scan(fd);
  std::sort(roots.begin(), roots.end());
  if (roots.size() != p) throw std::invalid_argument("ar_to_lsf: could not isolate the LSFs (roots too close)");
  return roots;
}

// --- model set -------------------------------------------------------------------

/// One AR/ARMA model of the acceleration at one (speed, force) point.
struct HattModel {
  double speed{0.0};              ///< tangential speed of the recording [file unit, mm/s in HaTT]
  double force{0.0};              ///< normal force of the recording [N]
  std::vector<double> ar_lsf;     ///< AR line spectral frequencies [rad], p values
  std::vector<double> ma_lsf;     ///< MA line spectral frequencies [rad], q values (ARMA only)
  std::vector<double> ar_coeff;   ///< AR coefficients as stored in the file (may be empty)
  std::vector<double> ma_coeff;   ///< MA coefficients as stored in the file (may be empty)
  double variance{0.0};           ///< variance of the driving noise [(acceleration unit)^2]
  double gain{1.0};               ///< MA gain (ARMA models)
};

/// A HaTT modelSet (one material).
struct HattModelSet {
  std::string name;                         ///< file stem or <htmlName>
  double mu{0.0};                           ///< kinetic friction coefficient [-]
  double max_speed{0.0};                    ///< largest modelled speed [file unit]
  double max_force{0.0};                    ///< largest modelled force [N]
  double sample_rate{10000.0};              ///< model sample rate [Hz] (HaTT: 10 kHz)
  double speed_to_file{1000.0};             ///< file speed units per m/s (1000: mm/s)
  double acceleration_to_si{1.0};           ///< m/s^2 per file acceleration unit
  std::vector<double> speeds;               ///< vertex speeds [file unit]
  std::vector<double> forces;               ///< vertex forces [N]
  std::vector<std::array<int, 3>> triangles;  ///< Delaunay triangles, 0-based vertex indices
  std::size_t ar_order{0};                  ///< p
  std::size_t ma_order{0};                  ///< q (0: AR model)
  std::vector<HattModel> models;            ///< models[i] sits at (speeds[i], forces[i])
};

namespace detail {

[[noreturn]] inline void hatt_fail(std::string_view source, const std::string& what) {
  throw std::invalid_argument(cat("HaTT model set", source.empty() ? "" : " '", source, source.empty() ? "" : "'", ": ", what));
}

inline double hatt_number(const xml::Node& node, std::string_view source, const std::string& field) {
  std::string_view t = node.text;
  while (!t.empty() && (t.front() == ' ' || t.front() == '\n' || t.front() == '\r' || t.front() == '\t')) t.remove_prefix(1);
  while (!t.empty() && (t.back() == ' ' || t.back() == '\n' || t.back() == '\r' || t.back() == '\t')) t.remove_suffix(1);
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
    hatt_fail(source, cat(field, " is not a finite number: '", t, "'"));
  return v;
}

inline const xml::Node& hatt_required(const xml::Node& parent, std::string_view name, std::string_view source) {
  const xml::Node* n = parent.child(name);
  if (!n) hatt_fail(source, cat("missing <", name, "> in <", parent.name, ">"));
  return *n;
}

inline double hatt_required_number(const xml::Node& parent, std::string_view name, std::string_view source) {
  return hatt_number(hatt_required(parent, name, source), source, cat("<", name, ">"));
}

inline std::size_t hatt_count(const xml::Node& parent, std::string_view name, std::string_view source) {
  const double v = hatt_required_number(parent, name, source);
  if (v < 0.0 || v > 1e6 || v != std::floor(v))
    hatt_fail(source, cat("<", name, "> must be a non-negative integer"));
  return static_cast<std::size_t>(v);
}

/// Values of <value> children (the HaTT list convention); a list may also
/// hold its numbers as whitespace-separated text.
inline std::vector<double> hatt_list(const xml::Node& list, std::string_view source) {
  std::vector<double> out;
  const auto values = list.children_named("value");
  if (!values.empty()) {
    for (const auto* v : values) out.push_back(hatt_number(*v, source, cat("<", list.name, "><value>")));
    return out;
  }
  std::istringstream in(list.text);
  std::string token;
  while (in >> token) {
    xml::Node tmp;
    tmp.text = token;
    out.push_back(hatt_number(tmp, source, cat("<", list.name, ">")));
  }
  return out;
}

inline void hatt_check_lsf(const std::vector<double>& lsf, std::string_view source, const std::string& what) {
  for (std::size_t i = 0; i < lsf.size(); ++i)
    if (!(lsf[i] > 0.0 && lsf[i] < std::numbers::pi) || (i > 0 && !(lsf[i] > lsf[i - 1])))
      hatt_fail(source, what + " must increase strictly within (0, pi) [rad]");
}

}  // namespace detail

/// Parses a modelSet document.
///
/// Required: <modelSet> with <mu>, <numMod>, <numTri>, <speedList>,
/// <forceList>, <tri> x numTri (three vertex indices each, 1-based as written
/// by MATLAB, or 0-based when an index 0 occurs), <numARCoeff>,
/// <numMACoeff>, and numMod <model> elements each with <ARlsf> (or
/// <ARcoeff>), <var>, <speedMod>, <forceMod>, plus <MAlsf> and <gain> when
/// numMACoeff > 0. Optional: <maxSpeed>, <maxForce>, <htmlName>,
/// <sampleRate> [Hz] (default 10000), <speedUnits> ("mm/s" default or "m/s"),
/// <accelUnits> ("m/s^2" default or "g"), <ARcoeff>, <MAcoeff>.
/// @throws std::invalid_argument naming the file and the field for
///         malformed XML, missing or non-numeric fields, counts that do not
///         match, indices out of range, degenerate triangles, LSFs not
///         increasing in (0, pi), or a negative variance.
[[nodiscard]] inline HattModelSet parse_hatt_model_set(std::string_view text, std::string_view source = {}) {
  using namespace detail;
  const xml::Node root = xml::parse(text, source);
  if (root.name != "modelSet") hatt_fail(source, cat("root element is <", root.name, ">, expected <modelSet>"));
  HattModelSet set;
  set.name = std::string(source);
  if (const auto* n = root.child("htmlName")) set.name = n->text;
  set.mu = hatt_required_number(root, "mu", source);
  if (set.mu < 0.0) hatt_fail(source, "<mu> must be >= 0");
  const std::size_t num_mod = hatt_count(root, "numMod", source);
  const std::size_t num_tri = hatt_count(root, "numTri", source);
  if (num_mod < 1) hatt_fail(source, "<numMod> must be >= 1");
  set.ar_order = hatt_count(root, "numARCoeff", source);
  set.ma_order = hatt_count(root, "numMACoeff", source);
  if (set.ar_order < 1) hatt_fail(source, "<numARCoeff> must be >= 1");
  if (const auto* n = root.child("sampleRate")) {
    set.sample_rate = hatt_number(*n, source, "<sampleRate>");
    if (set.sample_rate <= 0.0) hatt_fail(source, "<sampleRate> must be > 0 [Hz]");
  }
  if (const auto* n = root.child("speedUnits")) {
    if (n->text == "mm/s") set.speed_to_file = 1000.0;
    else if (n->text == "m/s") set.speed_to_file = 1.0;
    else hatt_fail(source, "<speedUnits> must be mm/s or m/s");
  }
  if (const auto* n = root.child("accelUnits")) {
    if (n->text == "m/s^2") set.acceleration_to_si = 1.0;
    else if (n->text == "g") set.acceleration_to_si = 9.80665;
    else hatt_fail(source, "<accelUnits> must be m/s^2 or g");
  }
  set.speeds = hatt_list(hatt_required(root, "speedList", source), source);
  set.forces = hatt_list(hatt_required(root, "forceList", source), source);
  if (set.speeds.size() != num_mod || set.forces.size() != num_mod)
    hatt_fail(source, cat("<speedList> and <forceList> must hold numMod = ", std::to_string(num_mod), " values"));
  double max_s = 0, max_f = 0;
  for (std::size_t i = 0; i < num_mod; ++i) max_s = std::max(max_s, set.speeds[i]), max_f = std::max(max_f, set.forces[i]);
  set.max_speed = root.child("maxSpeed") ? hatt_required_number(root, "maxSpeed", source) : max_s;
  set.max_force = root.child("maxForce") ? hatt_required_number(root, "maxForce", source) : max_f;

  const auto tris = root.children_named("tri");
  if (tris.size() != num_tri) hatt_fail(source, cat("found ", std::to_string(tris.size()), " <tri>, <numTri> says ", std::to_string(num_tri)));
  if (num_mod >= 3 && num_tri < 1) hatt_fail(source, cat("no <tri> for ", std::to_string(num_mod), " models"));
  std::vector<std::array<double, 3>> raw;
  double min_index = std::numeric_limits<double>::infinity();
  for (const auto* t : tris) {
    const std::vector<double> v = hatt_list(*t, source);
    if (v.size() != 3) hatt_fail(source, "each <tri> must hold three vertex indices");
    for (double x : v) {
      if (x != std::floor(x)) hatt_fail(source, "<tri> indices must be integers");
      min_index = std::min(min_index, x);
    }
    raw.push_back({v[0], v[1], v[2]});
  }
  const double base = min_index == 0.0 ? 0.0 : 1.0;
  for (const auto& r : raw) {
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const double idx = r[static_cast<std::size_t>(k)] - base;
      if (idx < 0.0 || idx >= static_cast<double>(num_mod)) hatt_fail(source, "<tri> vertex index out of range");
      t[static_cast<std::size_t>(k)] = static_cast<int>(idx);
    }
    const double ax = set.speeds[static_cast<std::size_t>(t[1])] - set.speeds[static_cast<std::size_t>(t[0])];
    const double ay = set.forces[static_cast<std::size_t>(t[1])] - set.forces[static_cast<std::size_t>(t[0])];
    const double bx = set.speeds[static_cast<std::size_t>(t[2])] - set.speeds[static_cast<std::size_t>(t[0])];
    const double by = set.forces[static_cast<std::size_t>(t[2])] - set.forces[static_cast<std::size_t>(t[0])];
    if (std::fabs(ax * by - ay * bx) <= 1e-12 * (std::fabs(ax * by) + std::fabs(ay * bx) + 1e-300))
      hatt_fail(source, "degenerate <tri> (its vertices are collinear)");
    set.triangles.push_back(t);
  }

  const auto models = root.children_named("model");
  if (models.size() != num_mod) hatt_fail(source, cat("found ", std::to_string(models.size()), " <model>, <numMod> says ", std::to_string(num_mod)));
  std::vector<HattModel> parsed;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const xml::Node& m = *models[i];
    const std::string where = cat("<model> ", std::to_string(i + 1));
    HattModel h;
    h.speed = hatt_required_number(m, "speedMod", source);
    h.force = hatt_required_number(m, "forceMod", source);
    h.variance = hatt_required_number(m, "var", source);
    if (h.variance < 0.0) hatt_fail(source, where + ": <var> must be >= 0 (negative variance)");
    if (const auto* n = m.child("ARcoeff")) h.ar_coeff = hatt_list(*n, source);
    if (const auto* n = m.child("MAcoeff")) h.ma_coeff = hatt_list(*n, source);
    if (const auto* n = m.child("ARlsf")) {
      h.ar_lsf = hatt_list(*n, source);
    } else if (!h.ar_coeff.empty()) {
      std::vector<double> a = h.ar_coeff;
      if (a.size() == set.ar_order) a.insert(a.begin(), 1.0);
      try {
        h.ar_lsf = ar_to_lsf(a);
      } catch (const std::invalid_argument& e) {
        hatt_fail(source, cat(where, ": <ARcoeff>: ", e.what()));
      }
    } else {
      hatt_fail(source, where + ": missing <ARlsf> (or <ARcoeff>)");
    }
    if (h.ar_lsf.size() != set.ar_order) hatt_fail(source, where + ": <ARlsf> must hold numARCoeff values");
    hatt_check_lsf(h.ar_lsf, source, where + ": <ARlsf>");
    if (set.ma_order > 0) {
      h.ma_lsf = hatt_list(hatt_required(m, "MAlsf", source), source);
      if (h.ma_lsf.size() != set.ma_order) hatt_fail(source, where + ": <MAlsf> must hold numMACoeff values");
      hatt_check_lsf(h.ma_lsf, source, where + ": <MAlsf>");
      h.gain = hatt_required_number(m, "gain", source);
    } else if (m.child("gain")) {
      h.gain = hatt_required_number(m, "gain", source);
    }
    parsed.push_back(std::move(h));
  }
  // order the models like the vertex lists: match <speedMod>/<forceMod> to
  // the list values (relative 1e-6), else keep the file's order
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
    if (found == num_mod && !used[v]) found = v;  // no value match: the file's order (the toolkit writes both in the same order)
    if (found == num_mod) hatt_fail(source, cat("no <model> for vertex ", std::to_string(v + 1), " of the lists"));
    used[found] = true;
    set.models[v] = parsed[found];
  }
  return set;
}

/// Reads and parses a modelSet file.
/// @throws std::invalid_argument when the file cannot be read or is invalid.
[[nodiscard]] inline HattModelSet load_hatt_model_set(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(detail::cat("HaTT model set: cannot open '", path.string(), "'"));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (text.size() > (std::size_t{64} << 20)) throw std::invalid_argument(detail::cat("HaTT model set: '", path.string(), "' is larger than 64 MB"));
  HattModelSet set = parse_hatt_model_set(text, path.filename().string());
  if (!set.name.empty() && set.name == path.filename().string()) set.name = path.stem().string();
  return set;
}

/// The modelSet files (*.xml, sorted) in a directory such as HaTT's XML/.
/// @throws std::invalid_argument when the directory does not exist.
[[nodiscard]] inline std::vector<std::filesystem::path> hatt_model_files(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) throw std::invalid_argument(detail::cat("HaTT: not a directory: '", dir.string(), "'"));
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".xml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

// --- triangulation -------------------------------------------------------------------

/// Barycentric location of a point in the triangulation.
struct Barycentric {
  std::array<int, 3> vertex{0, 0, 0};       ///< model indices
  std::array<double, 3> weight{1.0, 0.0, 0.0};  ///< >= 0, sum 1
  bool inside{true};                        ///< false: projected from outside the hull
  std::size_t triangle{0};                  ///< index of the triangle used
};

/// Point location in the (speed, force) Delaunay triangulation.
class HattTriangulation {
 public:
  HattTriangulation() = default;
  /// @throws std::invalid_argument for an index out of range or a degenerate triangle.
  HattTriangulation(std::vector<double> speeds, std::vector<double> forces, const std::vector<std::array<int, 3>>& triangles)
      : speeds_(std::move(speeds)), forces_(std::move(forces)) {
    if (speeds_.size() != forces_.size() || speeds_.empty())
      throw std::invalid_argument("HattTriangulation: need as many speeds as forces (>= 1)");
    for (const auto& t : triangles) {
      for (int v : t)
        if (v < 0 || static_cast<std::size_t>(v) >= speeds_.size())
          throw std::invalid_argument("HattTriangulation: vertex index out of range");
      Tri tri;
      tri.v = t;
      tri.s0 = speeds_[static_cast<std::size_t>(t[0])];
      tri.f0 = forces_[static_cast<std::size_t>(t[0])];
      const double a = speeds_[static_cast<std::size_t>(t[1])] - tri.s0, b = speeds_[static_cast<std::size_t>(t[2])] - tri.s0;
      const double c = forces_[static_cast<std::size_t>(t[1])] - tri.f0, d = forces_[static_cast<std::size_t>(t[2])] - tri.f0;
      const double det = a * d - b * c;
      if (!(std::fabs(det) > 0.0) || !std::isfinite(det)) throw std::invalid_argument("HattTriangulation: degenerate triangle");
      tri.inv = {d / det, -b / det, -c / det, a / det};
      tris_.push_back(tri);
    }
  }

  /// Locates (speed, force); outside the hull the weights of the nearest
  /// triangle (largest smallest weight) are clipped to >= 0 and
  /// renormalised. With no triangle (fewer than 3 models) the first model.
  /// `hint`: a triangle to try first (the previous answer: strokes move
  /// slowly through the triangulation).
  [[nodiscard]] Barycentric locate(double speed, double force, std::size_t hint = 0) const noexcept {
    Barycentric out;
    if (tris_.empty()) return out;
    double best = -std::numeric_limits<double>::infinity();
    std::size_t best_i = 0;
    std::array<double, 3> best_w{1.0, 0.0, 0.0};
    const std::size_t n = tris_.size();
    const std::size_t first = hint < n ? hint : 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = k == 0 ? first : (k <= first ? k - 1 : k);  // hint, then the others in order
      const auto w = weights(tris_[i], speed, force);
      const double m = std::min(w[0], std::min(w[1], w[2]));
      if (m > best) best = m, best_i = i, best_w = w;
      if (m >= -1e-12) break;
    }
    out.vertex = tris_[best_i].v;
    out.triangle = best_i;
    out.inside = best >= -1e-12;
    double total = 0.0;
    for (double& w : best_w) total += (w = std::max(w, 0.0));
    if (!(total > 0.0)) best_w = {1.0, 0.0, 0.0}, total = 1.0;
    for (int k = 0; k < 3; ++k) out.weight[static_cast<std::size_t>(k)] = best_w[static_cast<std::size_t>(k)] / total;
    return out;
  }

  [[nodiscard]] std::size_t size() const noexcept { return tris_.size(); }

 private:
  struct Tri {
    std::array<int, 3> v{};
    double s0{0}, f0{0};
    std::array<double, 4> inv{};  // inverse of [[a b][c d]]
  };
  static std::array<double, 3> weights(const Tri& t, double s, double f) noexcept {
    const double ds = s - t.s0, df = f - t.f0;
    const double w1 = t.inv[0] * ds + t.inv[1] * df;
    const double w2 = t.inv[2] * ds + t.inv[3] * df;
    return {1.0 - w1 - w2, w1, w2};
  }
  std::vector<double> speeds_;
  std::vector<double> forces_;
  std::vector<Tri> tris_;
};

// --- rendering ---------------------------------------------------------------------------

struct HattParams {
  double effective_mass{0.05};            ///< acceleration [m/s^2] -> force [N] (stylus + hand) [kg]
  glm::dvec3 surface_normal{0.0, 0.0, 1.0};  ///< unit; vibration along it, speed and friction in the tangent plane
  std::uint32_t seed{1};                  ///< noise seed
  int update_every{1};                    ///< ticks between coefficient updates (>= 1)
  double velocity_threshold{1e-3};        ///< silent below this tangential speed [m/s]
  bool friction{true};                    ///< add mu |Fc| Coulomb friction
  /// Run the model at its own sample rate: round(sample rate x tick period)
  /// AR steps per tick (at most max_hatt_steps_per_tick), output the newest,
  /// so a 10 kHz model in a 1 kHz loop keeps its spectrum below the loop's
  /// Nyquist frequency instead of being compressed ten times. false: one
  /// step per tick.
  bool match_sample_rate{true};
};

/// Most AR steps one tick runs when matching the model's sample rate.
inline constexpr int max_hatt_steps_per_tick = 256;

/// A HaTT model set as a HapticField. MaxOrder bounds the AR and MA orders
/// (storage is fixed at construction; force() never allocates). The model
/// runs at its own sample rate (HaTT models are identified at 10 kHz): each
/// tick advances it by the tick's period and renders the newest sample, so
/// content above the loop's Nyquist frequency folds down, as any sampled
/// display of the signal would.
template <std::size_t MaxOrder = 32>
class HattTexture {
 public:
  /// @throws std::invalid_argument for orders above MaxOrder, a bad
  ///         effective mass, normal or update period, or an invalid set.
  HattTexture(const HattModelSet& set, const HattParams& params)
      : tri_(set.speeds, set.forces, set.triangles), p_(params), p_order_(set.ar_order), q_order_(set.ma_order),
        mu_(set.mu), speed_to_file_(set.speed_to_file), accel_to_si_(set.acceleration_to_si),
        sample_rate_(set.sample_rate) {
    if (set.ar_order < 1 || set.ar_order > MaxOrder || set.ma_order > MaxOrder)
      throw std::invalid_argument("HattTexture: AR/MA order above MaxOrder");
    if (!std::isfinite(params.effective_mass) || params.effective_mass < 0.0)
      throw std::invalid_argument("HattTexture: effective_mass must be finite and >= 0 [kg]");
    if (std::fabs(glm::length(params.surface_normal) - 1.0) > 1e-9)
      throw std::invalid_argument("HattTexture: surface_normal must be a unit vector");
    if (params.update_every < 1) throw std::invalid_argument("HattTexture: update_every must be >= 1 [ticks]");
    if (!std::isfinite(params.velocity_threshold) || params.velocity_threshold < 0.0)
      throw std::invalid_argument("HattTexture: velocity_threshold must be finite and >= 0 [m/s]");
    if (set.models.size() != set.speeds.size()) throw std::invalid_argument("HattTexture: one model per vertex needed");
    for (const auto& m : set.models) {
      if (m.ar_lsf.size() != p_order_ || m.ma_lsf.size() != q_order_)
        throw std::invalid_argument("HattTexture: every model needs numARCoeff AR and numMACoeff MA LSFs");
      ar_lsf_.insert(ar_lsf_.end(), m.ar_lsf.begin(), m.ar_lsf.end());
      ma_lsf_.insert(ma_lsf_.end(), m.ma_lsf.begin(), m.ma_lsf.end());
      variance_.push_back(m.variance);
      gain_.push_back(m.gain);
    }
    update(0.0, 0.0);
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!is_finite(probe.velocity) || !std::isfinite(probe.normal_force)) return glm::dvec3{0.0};
    const glm::dvec3 n = p_.surface_normal;
    const glm::dvec3 vt = probe.velocity - glm::dot(probe.velocity, n) * n;
    const double speed = glm::length(vt);
    if (speed < p_.velocity_threshold) return glm::dvec3{0.0};
    const double fn = std::fabs(probe.normal_force);
    if (++since_update_ >= p_.update_every) {
      since_update_ = 0;
      update(speed * speed_to_file_, fn);
    }
    const int steps = steps_per_tick(probe.period);
    double y = 0.0;
    for (int i = 0; i < steps; ++i) y = step();
    acceleration_ = y * accel_to_si_;
    glm::dvec3 f = p_.effective_mass * acceleration_ * n;
    if (p_.friction) f -= (mu_ * fn / speed) * vt;
    return is_finite(f) ? f : glm::dvec3{0.0};
  }

  /// AR steps one tick of `period` [s] runs (see HattParams::match_sample_rate).
  [[nodiscard]] int steps_per_tick(double period) const noexcept {
    if (!p_.match_sample_rate) return 1;
    const double steps = std::round(sample_rate_ * period);
    if (!std::isfinite(steps) || steps < 1.0) return 1;
    return steps > max_hatt_steps_per_tick ? max_hatt_steps_per_tick : static_cast<int>(steps);
  }

  void reset() noexcept {
    x_hist_.fill(0.0);
    y_hist_.fill(0.0);
    tick_ = 0;
    since_update_ = 0;
    acceleration_ = 0.0;
  }

  /// Recomputes the filter for (speed [file unit], force [N]): locate,
  /// interpolate LSFs, variance and gain, convert to AR / MA polynomials.
  /// noexcept and allocation-free; called from force() every update_every
  /// ticks, or by the user from another place in the loop.
  void update(double speed_file_units, double force) noexcept {
    where_ = tri_.locate(speed_file_units, force, where_.triangle);
    std::array<double, MaxOrder> lsf{};
    cur_variance_ = 0.0;
    cur_gain_ = 0.0;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(where_.vertex[static_cast<std::size_t>(k)]);
      const double w = where_.weight[static_cast<std::size_t>(k)];
      for (std::size_t i = 0; i < p_order_; ++i) lsf[i] += w * ar_lsf_[v * p_order_ + i];
      cur_variance_ += w * variance_[v];
      cur_gain_ += w * gain_[v];
    }
    (void)lsf_to_ar<MaxOrder>(std::span<const double>(lsf.data(), p_order_), std::span<double>(ar_.data(), p_order_ + 1));
    if (q_order_ > 0) {
      std::array<double, MaxOrder> mlsf{};
      for (int k = 0; k < 3; ++k) {
        const auto v = static_cast<std::size_t>(where_.vertex[static_cast<std::size_t>(k)]);
        const double w = where_.weight[static_cast<std::size_t>(k)];
        for (std::size_t i = 0; i < q_order_; ++i) mlsf[i] += w * ma_lsf_[v * q_order_ + i];
      }
      (void)lsf_to_ar<MaxOrder>(std::span<const double>(mlsf.data(), q_order_), std::span<double>(ma_.data(), q_order_ + 1));
    }
  }

  /// Current AR polynomial a_0 = 1, a_1..a_p.
  [[nodiscard]] std::span<const double> ar_coefficients() const noexcept { return {ar_.data(), p_order_ + 1}; }
  /// Current MA polynomial b_0..b_q (empty for AR models).
  [[nodiscard]] std::span<const double> ma_coefficients() const noexcept { return {ma_.data(), q_order_ > 0 ? q_order_ + 1 : 0}; }
  [[nodiscard]] double variance() const noexcept { return cur_variance_; }
  [[nodiscard]] const Barycentric& location() const noexcept { return where_; }
  /// Last synthesised acceleration [m/s^2].
  [[nodiscard]] double acceleration() const noexcept { return acceleration_; }

 private:
  /// One AR / ARMA step at the model's sample rate: returns y [file units].
  double step() noexcept {
    const double x = std::sqrt(cur_variance_) * gaussian(p_.seed, Cell{tick_++, 0, 0});
    double y = x;
    if (q_order_ > 0) {
      y = ma_[0] * x;
      for (std::size_t k = 1; k <= q_order_; ++k) y += ma_[k] * x_hist_[k - 1];
      y *= cur_gain_;
      for (std::size_t k = q_order_; k-- > 1;) x_hist_[k] = x_hist_[k - 1];
      x_hist_[0] = x;
    }
    for (std::size_t k = 1; k <= p_order_; ++k) y -= ar_[k] * y_hist_[k - 1];
    for (std::size_t k = p_order_; k-- > 1;) y_hist_[k] = y_hist_[k - 1];
    y_hist_[0] = y;
    return y;
  }

  HattTriangulation tri_;
  HattParams p_;
  std::size_t p_order_;
  std::size_t q_order_;
  double mu_;
  double speed_to_file_;
  double accel_to_si_;
  double sample_rate_;  ///< [Hz]
  std::vector<double> ar_lsf_;    // models x p
  std::vector<double> ma_lsf_;    // models x q
  std::vector<double> variance_;
  std::vector<double> gain_;
  Barycentric where_{};
  std::array<double, MaxOrder + 1> ar_{};
  std::array<double, MaxOrder + 1> ma_{};
  std::array<double, MaxOrder> x_hist_{};
  std::array<double, MaxOrder> y_hist_{};
  double cur_variance_{0.0};
  double cur_gain_{1.0};
  double acceleration_{0.0};
  std::uint32_t tick_{0};
  int since_update_{0};
};

}  // namespace hapticfield::texture

#pragma once
/// @file band_synthesis.hpp
/// Renders the haptic media model (haptic_media.hpp) to sampled signals at
/// any output rate and any timescale: every sample is a closed form of its
/// time, so a rate or a timescale changes where the signal is sampled, never
/// the signal. Setup-side code (allocates, never runs in a tick); playback
/// plays the buffers it makes (material/haptic_playback.hpp).
///
/// Band types (ISO/IEC 23090-31 bands; docs/hjif.md says where the MPEG
/// reference synthesizer differs and which way this follows):
///   VectorialWave  A(t) x wave(Phi(t)): amplitude keyframes linear in time
///                  (held before the first, after the last), frequency
///                  keyframes linear in time (a linear chirp between two),
///                  Phi(t) = phase + 2 pi integral of f: phase-continuous;
///                  base signals Sine, Square, Triangle, SawToothUp/Down,
///                  all aligned so that they rise through phase 0 like a sine.
///   Curve          the amplitude keyframes interpolated by curve_type:
///                  Linear; Cubic (and Unknown) a cubic Hermite with zero
///                  slope at each keyframe; Akima; Bezier (quadratic, every
///                  other keyframe a control point); Bspline (clamped
///                  quadratic, the keyframes its control points).
///   Transient      per keyframe, two periods of a sine at the keyframe's
///                  frequency (90.9 Hz, the reference's 22 ms, without one),
///                  scaled by its amplitude.
///   WaveletWave    each effect one block of block_length [ms] at
///                  upper_frequency_limit [Hz] samples per second, decoded by
///                  wavelet_synthesis.hpp and held sample by sample (as the
///                  reference); blocks past a budget of
///                  max_wavelet_samples are skipped.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "hapticfield/material/haptic_media.hpp"
#include "hapticfield/material/wavelet_synthesis.hpp"

namespace hapticfield::material {

/// Transient without a frequency: two periods in 22 ms, as the reference software [Hz].
inline constexpr double default_transient_frequency = 2.0 / 0.022;
/// Longest signal render_media makes [s] (a file may place an effect at tick 2^62).
inline constexpr double max_render_seconds = 3600.0;
/// Most WaveletWave samples decoded per band (bounds the work a hostile file can ask for).
inline constexpr std::size_t max_wavelet_samples = std::size_t{1} << 26;
/// Highest WaveletWave sampling rate (upper_frequency_limit) decoded [Hz].
inline constexpr double max_wavelet_rate = 384000.0;
/// Output rates render_media accepts [Hz].
inline constexpr double min_render_rate = 1.0;
inline constexpr double max_render_rate = 384000.0;

namespace detail {

struct TimedValue {
  double t{0.0};  ///< from the effect's position [s]
  double v{0.0};
};

[[nodiscard]] inline double ticks(const Keyframe& k) noexcept {
  return static_cast<double>(k.relative_position.value_or(0));
}

/// Piecewise-linear value at t, held before the first and after the last point.
[[nodiscard]] inline double linear_at(const std::vector<TimedValue>& p, double t) noexcept {
  if (p.empty()) return 0.0;
  if (t <= p.front().t) return p.front().v;
  if (t >= p.back().t) return p.back().v;
  const auto it = std::upper_bound(p.begin(), p.end(), t, [](double x, const TimedValue& q) { return x < q.t; });
  const TimedValue& b = *it;
  const TimedValue& a = *(it - 1);
  const double h = b.t - a.t;
  return h > 0.0 ? a.v + (b.v - a.v) * (t - a.t) / h : b.v;
}

/// The base signals as functions of the phase [rad], each rising through 0 at phase 0.
[[nodiscard]] inline double base_wave(BaseSignal s, double phase) noexcept {
  const double u = phase / (2.0 * std::numbers::pi);  // cycles
  switch (s) {
    case BaseSignal::sine:
      return std::sin(phase);
    case BaseSignal::square:
      return (u - std::floor(u)) < 0.5 ? 1.0 : -1.0;
    case BaseSignal::triangle: {
      const double w = u - 0.25;
      return 1.0 - 4.0 * std::abs(std::round(w) - w);
    }
    case BaseSignal::saw_tooth_up:
      return 2.0 * (u - std::floor(u + 0.5));
    case BaseSignal::saw_tooth_down:
      return -2.0 * (u - std::floor(u + 0.5));
  }
  return 0.0;
}

/// A VectorialWave effect prepared for sampling: amplitude and frequency
/// tracks and the accumulated phase at each frequency keyframe.
class VectorialPlan {
 public:
  VectorialPlan(const Effect& e, double timescale) : signal_(e.base_signal) {
    for (const Keyframe& k : e.keyframes) {
      const double t = ticks(k) / timescale;
      if (k.amplitude) amplitude_.push_back({t, *k.amplitude});
      if (k.frequency) frequency_.push_back({t, *k.frequency});
      end_ = std::max(end_, t);
    }
    // Phi at each frequency keyframe: f held at f0 before the first, trapezoids (a linear chirp) between.
    double phi = e.phase;
    for (std::size_t i = 0; i < frequency_.size(); ++i) {
      if (i == 0)
        phi += 2.0 * std::numbers::pi * frequency_[0].v * frequency_[0].t;
      else
        phi += std::numbers::pi * (frequency_[i].t - frequency_[i - 1].t) * (frequency_[i].v + frequency_[i - 1].v);
      phase_at_.push_back(phi);
    }
    start_phase_ = e.phase;
  }
  [[nodiscard]] double end() const noexcept { return end_; }  ///< [s] from the effect's start
  /// Instantaneous frequency at t [Hz].
  [[nodiscard]] double frequency(double t) const noexcept { return linear_at(frequency_, t); }
  /// Phase at t [rad]: the integral of frequency(t) from 0 plus the effect's phase.
  [[nodiscard]] double phase(double t) const noexcept {
    const auto& f = frequency_;
    if (f.empty()) return start_phase_;
    if (t <= f.front().t) return start_phase_ + 2.0 * std::numbers::pi * f.front().v * t;
    const auto it = std::upper_bound(f.begin(), f.end(), t, [](double x, const TimedValue& q) { return x < q.t; });
    const auto i = static_cast<std::size_t>(it - f.begin()) - 1;
    const double s = t - f[i].t;
    if (it == f.end()) return phase_at_[i] + 2.0 * std::numbers::pi * f[i].v * s;
    const double h = f[i + 1].t - f[i].t;
    const double k = h > 0.0 ? (f[i + 1].v - f[i].v) / h : 0.0;  // [Hz/s]
    return phase_at_[i] + 2.0 * std::numbers::pi * (f[i].v * s + 0.5 * k * s * s);
  }
  [[nodiscard]] double value(double t) const noexcept {
    const double a = amplitude_.empty() ? 1.0 : linear_at(amplitude_, t);
    return a * base_wave(signal_, phase(t));
  }

 private:
  BaseSignal signal_;
  std::vector<TimedValue> amplitude_, frequency_;
  std::vector<double> phase_at_;
  double start_phase_{0.0};
  double end_{0.0};
};

/// Hermite cubic on [a, b] with slopes ma, mb [value/s].
[[nodiscard]] inline double hermite(const TimedValue& a, const TimedValue& b, double ma, double mb, double t) noexcept {
  const double h = b.t - a.t;
  if (!(h > 0.0)) return b.v;
  const double s = (t - a.t) / h, s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * a.v + (s3 - 2 * s2 + s) * h * ma + (-2 * s3 + 3 * s2) * b.v + (s3 - s2) * h * mb;
}

/// Akima slopes (Akima 1970, J. ACM 17(4)) with the usual two extrapolated secants at each end.
[[nodiscard]] inline std::vector<double> akima_slopes(const std::vector<TimedValue>& p) {
  const std::size_t n = p.size();
  std::vector<double> m(n + 3);  // m[i + 2] = secant i
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double h = p[i + 1].t - p[i].t;
    m[i + 2] = h > 0.0 ? (p[i + 1].v - p[i].v) / h : 0.0;
  }
  m[1] = 2 * m[2] - m[3];
  m[0] = 3 * m[2] - 2 * m[3];
  m[n + 1] = 2 * m[n] - m[n - 1];
  m[n + 2] = 3 * m[n] - 2 * m[n - 1];
  std::vector<double> slope(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double w1 = std::abs(m[i + 3] - m[i + 2]), w2 = std::abs(m[i + 1] - m[i]);
    slope[i] = (w1 + w2) > 1e-12 * (std::abs(m[i + 1]) + std::abs(m[i + 2]) + 1e-300)
                   ? (w1 * m[i + 1] + w2 * m[i + 2]) / (w1 + w2)
                   : 0.5 * (m[i + 1] + m[i + 2]);
  }
  return slope;
}

/// Solves x(u) = t for u in [0, 1] on a non-decreasing x(u) by bisection (60 halvings: exact to double precision).
template <class X>
[[nodiscard]] double invert_monotone(X&& x, double t) noexcept {
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (x(mid) < t ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// A Curve effect prepared for sampling.
class CurvePlan {
 public:
  CurvePlan(const Effect& e, CurveType type, double timescale) : type_(type) {
    for (const Keyframe& k : e.keyframes)
      if (k.amplitude) points_.push_back({ticks(k) / timescale, *k.amplitude});
    if (points_.size() < 3 && (type_ == CurveType::akima || type_ == CurveType::bezier || type_ == CurveType::bspline))
      type_ = CurveType::linear;
    if (type_ == CurveType::akima) slopes_ = akima_slopes(points_);
    if (type_ == CurveType::bspline) {  // clamped uniform knots: 0,0,0, 1/(n-2), ..., 1,1,1
      const std::size_t n = points_.size();
      knots_.assign(n + 3, 0.0);
      for (std::size_t i = 0; i < n + 3; ++i)
        knots_[i] =
            std::clamp(static_cast<double>(static_cast<std::ptrdiff_t>(i) - 2) / static_cast<double>(n - 2), 0.0, 1.0);
    }
  }
  [[nodiscard]] bool empty() const noexcept { return points_.empty(); }
  [[nodiscard]] double begin() const noexcept { return points_.empty() ? 0.0 : points_.front().t; }
  [[nodiscard]] double end() const noexcept { return points_.empty() ? 0.0 : points_.back().t; }

  [[nodiscard]] double value(double t) const noexcept {
    const auto& p = points_;
    if (p.empty() || t < p.front().t || t > p.back().t) return 0.0;
    if (p.size() == 1) return p.front().v;
    if (type_ == CurveType::bspline) return bspline(t);
    const auto it = std::upper_bound(p.begin(), p.end(), t, [](double x, const TimedValue& q) { return x < q.t; });
    std::size_t i = it == p.end() ? p.size() - 2 : static_cast<std::size_t>(it - p.begin()) - 1;
    switch (type_) {
      case CurveType::linear:
        return linear_at(p, t);
      case CurveType::akima:
        return hermite(p[i], p[i + 1], slopes_[i], slopes_[i + 1], t);
      case CurveType::bezier:
        return bezier(i, t);
      case CurveType::unknown:
      case CurveType::cubic:
      case CurveType::bspline:
        break;
    }
    return hermite(p[i], p[i + 1], 0.0, 0.0, t);
  }

 private:
  /// Quadratic Bezier over (p[2j], p[2j+1], p[2j+2]); an even count ends on a line.
  [[nodiscard]] double bezier(std::size_t i, double t) const noexcept {
    const auto& p = points_;
    const std::size_t j = i - i % 2;
    if (j + 2 >= p.size()) return linear_at(p, t);
    const TimedValue a = p[j], c = p[j + 1], b = p[j + 2];
    const auto quad = [](double u, double x0, double x1, double x2) {
      return (1 - u) * (1 - u) * x0 + 2 * u * (1 - u) * x1 + u * u * x2;
    };
    const double u = invert_monotone([&](double s) { return quad(s, a.t, c.t, b.t); }, t);
    return quad(u, a.v, c.v, b.v);
  }
  /// Point of the clamped quadratic B-spline at parameter u (de Boor).
  [[nodiscard]] TimedValue bspline_point(double u) const noexcept {
    const std::size_t n = points_.size();
    std::size_t k = 2;  // knot span: knots_[k] <= u < knots_[k + 1]
    while (k + 1 < n && knots_[k + 1] <= u)
      ++k;
    TimedValue d[3] = {points_[k - 2], points_[k - 1], points_[k]};
    for (int r = 1; r <= 2; ++r)
      for (int j = 2; j >= r; --j) {
        const std::size_t i = k - 2 + static_cast<std::size_t>(j);
        const double den = knots_[i + 3 - static_cast<std::size_t>(r)] - knots_[i];
        const double a = den > 0.0 ? (u - knots_[i]) / den : 0.0;
        d[j] = {(1 - a) * d[j - 1].t + a * d[j].t, (1 - a) * d[j - 1].v + a * d[j].v};
      }
    return d[2];
  }
  [[nodiscard]] double bspline(double t) const noexcept {
    const double u = invert_monotone([&](double s) { return bspline_point(s).t; }, t);
    return bspline_point(u).v;
  }

  CurveType type_;
  std::vector<TimedValue> points_;
  std::vector<double> slopes_;
  std::vector<double> knots_;
};

/// Adds f(t) for the samples i with t = i / rate - t0 in [begin, end] [s] (t rounded into the span).
template <class F>
void add_span(std::vector<double>& out, double rate, double t0, double begin, double end, F&& f) {
  if (!(end >= begin) || out.empty()) return;
  const double first = std::ceil((t0 + begin) * rate - 1e-9), last = std::floor((t0 + end) * rate + 1e-9);
  if (last < 0.0 || first >= static_cast<double>(out.size())) return;
  const auto i0 = static_cast<std::size_t>(std::max(first, 0.0));
  const auto i1 = static_cast<std::size_t>(std::min(last, static_cast<double>(out.size() - 1)));
  for (std::size_t i = i0; i <= i1; ++i)
    out[i] += f(std::clamp(static_cast<double>(i) / rate - t0, begin, end));
}

}  // namespace detail

/// The effect a band's effect stands for: a Reference effect's library entry
/// (at the referring effect's position), or the effect itself. nullptr for a
/// Reference to a missing id and for Composite effects (not rendered).
[[nodiscard]] inline const Effect* resolve_effect(const Perception& p, const Effect& e) noexcept {
  if (e.type == EffectType::basis) return &e;
  if (e.type == EffectType::reference) {
    for (const Effect& l : p.effect_library)
      if (l.id == e.id && l.type == EffectType::basis) return &l;
  }
  return nullptr;
}

/// End of one effect [ticks from its position]: the last keyframe (Transient: plus its burst).
[[nodiscard]] inline double effect_length_ticks(BandType band, const Effect& e, double timescale) noexcept {
  double end = 0.0;
  for (const Keyframe& k : e.keyframes) {
    double t = detail::ticks(k);
    if (band == BandType::transient && k.amplitude) {
      const double f = k.frequency.value_or(default_transient_frequency);
      if (f > 0.0) t += 2.0 / f * timescale;
    }
    end = std::max(end, t);
  }
  return end;
}

/// Samples of one WaveletWave block: block_length [ms] x upper_frequency_limit [Hz] (as the reference
/// Synthesizer reads block_length), 0 when that is not a power of two in [16, max_wavelet_block].
[[nodiscard]] inline std::size_t wavelet_block_samples(const Band& b) noexcept {
  if (!b.block_length || !(b.upper_frequency_limit > 0.0 && b.upper_frequency_limit <= max_wavelet_rate)) return 0;
  const double n = static_cast<double>(*b.block_length) * 1e-3 * b.upper_frequency_limit;
  if (!(n >= 16.0 && n <= static_cast<double>(max_wavelet_block))) return 0;
  const auto k = static_cast<std::size_t>(n);
  return (k & (k - 1)) == 0 ? k : 0;
}

/// Length of a channel [s]: the end of its last effect, or sample_count /
/// frequency_sampling where the channel has both (PCM-derived channels).
[[nodiscard]] inline double channel_duration(const HapticMedia& m, const Perception& p, const Channel& c) noexcept {
  const auto ts = static_cast<double>(m.timescale);
  if (c.frequency_sampling && c.sample_count && *c.frequency_sampling > 0)
    return static_cast<double>(*c.sample_count) / static_cast<double>(*c.frequency_sampling);
  double end = 0.0;
  for (const Band& b : c.bands)
    for (const Effect& e : b.effects) {
      const Effect* r = resolve_effect(p, e);
      if (r == nullptr) continue;
      if (b.type == BandType::wavelet_wave) {
        if (const std::size_t n = wavelet_block_samples(b); n > 0)
          end = std::max(end, static_cast<double>(e.position) / ts + static_cast<double>(n) / b.upper_frequency_limit);
        continue;
      }
      end = std::max(end, (static_cast<double>(e.position) + effect_length_ticks(b.type, *r, ts)) / ts);
    }
  return end;
}

/// Length of the whole media [s]: its longest channel.
[[nodiscard]] inline double media_duration(const HapticMedia& m) noexcept {
  double end = 0.0;
  for (const Perception& p : m.perceptions)
    for (const Channel& c : p.channels)
      end = std::max(end, channel_duration(m, p, c));
  return end;
}

/// Adds one band of a channel to `out` (sample i at time i / rate [s]).
inline void render_band(const HapticMedia& m, const Perception& p, const Band& band, double rate,
                        std::vector<double>& out) {
  const auto ts = static_cast<double>(m.timescale);
  if (band.type == BandType::wavelet_wave) {
    const std::size_t n = wavelet_block_samples(band);
    const double fs = band.upper_frequency_limit;
    std::size_t budget = max_wavelet_samples;
    for (const Effect& e : band.effects) {
      if (n == 0 || budget < n) break;
      budget -= n;
      const std::vector<double> block = decode_wavelet_block(e.wavelet_stream, n);
      const double t0 = static_cast<double>(e.position) / ts;
      detail::add_span(out, rate, t0, 0.0, static_cast<double>(n) / fs, [&](double t) {
        const auto k = static_cast<std::size_t>(std::floor(t * fs + 1e-9));  // held, as the reference
        return k < block.size() ? block[k] : 0.0;
      });
    }
    return;
  }
  for (const Effect& e : band.effects) {
    const Effect* r = resolve_effect(p, e);
    if (r == nullptr || r->keyframes.empty()) continue;
    const double t0 = static_cast<double>(e.position) / ts;  // effect start [s]
    switch (band.type) {
      case BandType::vectorial_wave: {
        const detail::VectorialPlan plan(*r, ts);
        detail::add_span(out, rate, t0, 0.0, plan.end(), [&](double t) { return plan.value(t); });
        break;
      }
      case BandType::curve: {
        const detail::CurvePlan plan(*r, band.curve_type, ts);
        if (!plan.empty())
          detail::add_span(out, rate, t0, plan.begin(), plan.end(), [&](double t) { return plan.value(t); });
        break;
      }
      case BandType::transient:
        for (const Keyframe& k : r->keyframes) {
          if (!k.amplitude) continue;
          const double f = k.frequency.value_or(default_transient_frequency);
          if (!(f > 0.0)) continue;
          const double tk = detail::ticks(k) / ts, a = *k.amplitude;
          detail::add_span(out, rate, t0, tk, tk + 2.0 / f,
                           [&](double t) { return a * std::sin(2.0 * std::numbers::pi * f * (t - tk)); });
        }
        break;
      case BandType::wavelet_wave:
        break;
    }
  }
}

/// One channel sampled at `rate` [Hz], `count` samples from time 0: the sum
/// of its bands clamped to [-1, 1] (as the reference software), times the
/// channel's gain and 10^perception_unit_exponent; non-finite samples are 0.
[[nodiscard]] inline std::vector<double> render_channel(const HapticMedia& m, const Perception& p, const Channel& c,
                                                        double rate, std::size_t count) {
  std::vector<double> out(count, 0.0);
  for (const Band& b : c.bands)
    render_band(m, p, b, rate, out);
  const double scale = c.gain * std::pow(10.0, static_cast<double>(p.perception_unit_exponent));
  for (double& y : out) {
    y = std::clamp(y, -1.0, 1.0) * scale;
    if (!std::isfinite(y)) y = 0.0;
  }
  return out;
}

/// Every channel of a media, in file order (perception by perception).
struct RenderedMedia {
  double rate{0.0};                           ///< [Hz]
  std::vector<std::vector<double>> channels;  ///< one signal per channel, all the same length
  std::vector<std::string> names;             ///< "perception 0 (Vibrotactile) channel 0"
};

/// Renders every channel at `rate` [Hz] over the media's duration.
/// @throws std::invalid_argument for a rate outside [1, 384000] Hz, a
///         non-positive timescale or a media longer than max_render_seconds.
[[nodiscard]] inline RenderedMedia render_media(const HapticMedia& m, double rate) {
  if (!(rate >= min_render_rate && rate <= max_render_rate))
    throw std::invalid_argument("render_media: rate must be within [1, 384000] Hz");
  if (m.timescale <= 0) throw std::invalid_argument("render_media: timescale must be > 0");
  const double duration = media_duration(m);
  if (!(duration <= max_render_seconds))
    throw std::invalid_argument("render_media: the media lasts " + std::to_string(duration) +
                                " s, longer than the limit of 3600 s");
  const auto count = static_cast<std::size_t>(std::floor(duration * rate + 1e-9)) + 1;
  RenderedMedia r;
  r.rate = rate;
  for (std::size_t pi = 0; pi < m.perceptions.size(); ++pi) {
    const Perception& p = m.perceptions[pi];
    for (std::size_t ci = 0; ci < p.channels.size(); ++ci) {
      r.channels.push_back(render_channel(m, p, p.channels[ci], rate, count));
      r.names.push_back("perception " + std::to_string(p.id) + " (" + p.modality + ") channel " +
                        std::to_string(p.channels[ci].id));
    }
  }
  return r;
}

}  // namespace hapticfield::material

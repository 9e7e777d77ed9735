#pragma once
/// @file haptic_media.hpp
/// The haptic media model of MPEG-I Haptics (ISO/IEC 23090-31), as a .hjif
/// file holds it: a media of perceptions, each with channels, each channel
/// with bands, each band with effects, each effect with keyframes. Plain
/// data: no file format here (io/hjif.hpp reads and writes it) and no
/// synthesis (material/band_synthesis.hpp renders it).
///
/// Positions are integer ticks of HapticMedia::timescale ticks per second.
/// Fields the model does not render (avatars, syncs, reference devices,
/// priorities, body-part targets, ...) and fields the reader does not know
/// stay in `extra` as raw JSON text under their key, so a write gives them
/// back unchanged. docs/hjif.md lists every field and what becomes of it.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hapticfield::material {

/// Raw JSON text of the fields kept but not modelled, in file order: (key, value).
using ExtraFields = std::vector<std::pair<std::string, std::string>>;

enum class BandType { transient, curve, vectorial_wave, wavelet_wave };
enum class CurveType { unknown, cubic, linear, akima, bezier, bspline };
enum class BaseSignal { sine, square, triangle, saw_tooth_up, saw_tooth_down };
enum class EffectType { basis, reference, composite };

/// One keyframe: any of its three values may be absent (an amplitude-only or
/// a frequency-only keyframe).
struct Keyframe {
  std::optional<std::int64_t> relative_position;  ///< from the effect's position [ticks]
  std::optional<double> amplitude;                ///< amplitude_modulation [-], nominal [-1, 1]
  std::optional<double> frequency;                ///< frequency_modulation [Hz]
};

struct Effect {
  EffectType type{EffectType::basis};
  std::int64_t id{-1};       ///< library id (Reference effects name one) or -1
  std::int64_t position{0};  ///< start in the band [ticks]
  double phase{0.0};         ///< VectorialWave start phase [rad]
  BaseSignal base_signal{BaseSignal::sine};
  std::vector<Keyframe> keyframes;
  std::string wavelet_stream;  ///< WaveletWave: base64 SPIHT block, kept verbatim
  ExtraFields extra;
};

struct Band {
  BandType type{BandType::vectorial_wave};
  CurveType curve_type{CurveType::unknown};  ///< Curve bands
  bool has_curve_type{false};                ///< curve_type was written (Curve bands always write it)
  double lower_frequency_limit{0.0};         ///< [Hz]
  double upper_frequency_limit{1000.0};      ///< [Hz]
  std::optional<std::int64_t> block_length;  ///< WaveletWave block [ticks]
  std::vector<Effect> effects;
  ExtraFields extra;
};

struct Channel {
  std::int64_t id{0};
  std::string description;
  double gain{1.0};                ///< output scale [-]
  double mixing_coefficient{1.0};  ///< weight when channels share an actuator [-] (kept, not applied)
  std::uint32_t body_part_mask{0};
  std::optional<std::int64_t> frequency_sampling;  ///< PCM-derived channels: the source's rate [Hz]
  std::optional<std::int64_t> sample_count;        ///< PCM-derived channels: the source's length [samples]
  std::vector<Band> bands;
  ExtraFields extra;
};

/// What a perception's modality means to this library's playback.
enum class ModalityKind { vibrotactile, force, other };

struct Perception {
  std::int64_t id{0};
  std::int64_t avatar_id{0};
  std::string description;
  std::string modality{"Other"};             ///< perception_modality, as written
  std::int64_t perception_unit_exponent{0};  ///< output x 10^exponent
  bool has_perception_unit_exponent{false};
  std::vector<Effect> effect_library;  ///< effects that Reference effects name by id
  std::vector<Channel> channels;
  ExtraFields extra;
};

struct HapticMedia {
  std::string version{"2023"};
  std::string profile{"Main"};
  std::int64_t level{1};
  std::string date;
  std::string description;
  std::int64_t timescale{1000};  ///< ticks per second
  std::vector<Perception> perceptions;
  ExtraFields extra;  ///< avatars, syncs and unknown top-level fields
};

/// The modality names of the reference software: vibration and force are
/// played; every other modality is kept and rendered as a signal only.
[[nodiscard]] inline ModalityKind modality_kind(std::string_view modality) noexcept {
  if (modality == "Vibrotactile" || modality == "Vibration" || modality == "VibrotactileTexture")
    return ModalityKind::vibrotactile;
  if (modality == "Force" || modality == "Pressure" || modality == "Stiffness") return ModalityKind::force;
  return ModalityKind::other;
}

[[nodiscard]] inline const char* band_type_name(BandType t) noexcept {
  switch (t) {
    case BandType::transient:
      return "Transient";
    case BandType::curve:
      return "Curve";
    case BandType::vectorial_wave:
      return "VectorialWave";
    case BandType::wavelet_wave:
      return "WaveletWave";
  }
  return "VectorialWave";
}
[[nodiscard]] inline const char* curve_type_name(CurveType t) noexcept {
  switch (t) {
    case CurveType::unknown:
      return "Unknown";
    case CurveType::cubic:
      return "Cubic";
    case CurveType::linear:
      return "Linear";
    case CurveType::akima:
      return "Akima";
    case CurveType::bezier:
      return "Bezier";
    case CurveType::bspline:
      return "Bspline";
  }
  return "Unknown";
}
[[nodiscard]] inline const char* base_signal_name(BaseSignal s) noexcept {
  switch (s) {
    case BaseSignal::sine:
      return "Sine";
    case BaseSignal::square:
      return "Square";
    case BaseSignal::triangle:
      return "Triangle";
    case BaseSignal::saw_tooth_up:
      return "SawToothUp";
    case BaseSignal::saw_tooth_down:
      return "SawToothDown";
  }
  return "Sine";
}
[[nodiscard]] inline const char* effect_type_name(EffectType t) noexcept {
  switch (t) {
    case EffectType::basis:
      return "Basis";
    case EffectType::reference:
      return "Reference";
    case EffectType::composite:
      return "Composite";
  }
  return "Basis";
}

}  // namespace hapticfield::material

#pragma once
/// @file hatt_model_set.hpp
/// The data of a Penn Haptic Texture Toolkit (HaTT) modelSet: AR / ARMA
/// models of the stylus acceleration at (speed, force) points, and their
/// Delaunay triangulation. Plain data; read from a file with
/// hapticfield/texture/hatt_model_file.hpp, rendered by
/// hapticfield/texture/hatt_texture.hpp.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace hapticfield::texture {

/// One AR/ARMA model of the acceleration at one (speed, force) point.
struct HattModel {
  double speed{0.0};             ///< tangential speed of the recording [file unit, mm/s in HaTT]
  double force{0.0};             ///< normal force of the recording [N]
  std::vector<double> ar_lsf;    ///< AR line spectral frequencies [rad], p values
  std::vector<double> ma_lsf;    ///< MA line spectral frequencies [rad], q values (ARMA only)
  std::vector<double> ar_coeff;  ///< AR coefficients as stored in the file (may be empty)
  std::vector<double> ma_coeff;  ///< MA coefficients as stored in the file (may be empty)
  double variance{0.0};          ///< variance of the driving noise [(acceleration unit)^2]
  double gain{1.0};              ///< MA gain (ARMA models)
};

/// A HaTT modelSet (one material).
struct HattModelSet {
  std::string name;                           ///< file stem or <htmlName>
  double mu{0.0};                             ///< kinetic friction coefficient [-]
  double max_speed{0.0};                      ///< largest modelled speed [file unit]
  double max_force{0.0};                      ///< largest modelled force [N]
  double sample_rate{10000.0};                ///< model sample rate [Hz] (HaTT: 10 kHz; resampled sets 1 kHz)
  double speed_to_file{1000.0};               ///< file speed units per m/s (1000: mm/s)
  double acceleration_to_si{1.0};             ///< m/s^2 per file acceleration unit
  std::vector<double> speeds;                 ///< vertex speeds [file unit]
  std::vector<double> forces;                 ///< vertex forces [N]
  std::vector<std::array<int, 3>> triangles;  ///< Delaunay triangles, 0-based vertex indices
  std::size_t ar_order{0};                    ///< p
  std::size_t ma_order{0};                    ///< q (0: AR model)
  std::vector<HattModel> models;              ///< models[i] sits at (speeds[i], forces[i])
};

}  // namespace hapticfield::texture

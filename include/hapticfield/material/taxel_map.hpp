#pragma once
/// @file taxel_map.hpp
/// TaxelTexture: a HaTT "taxel" map. An index picture over uv
/// (material/property_map.hpp, IndexMap) picks one HaTT modelSet (Culbertson,
/// Lopez Delgado & Kuchenbecker, IEEE Haptics Symposium 2014;
/// texture/hatt_texture.hpp) per region, so one surface can be canvas here
/// and metal there. Crossing a region border changes the model without a
/// click: every model's filter runs every tick (its state stays warm) and
/// the output is the models' forces weighted by the bilinear weights of the
/// four texels around the touched uv, so a model fades in over one texel as
/// the other fades out.
///
/// A part of a MaterialSurface (material/material_surface.hpp) or any
/// ContactField whose constraint reports uv. force() is noexcept and
/// allocation-free; its cost is max_taxel_models filters at most.

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/material/property_map.hpp"
#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/hatt_texture.hpp"

namespace hapticfield::material {

/// Most modelSets one taxel map switches between (each runs every tick).
inline constexpr std::size_t max_taxel_models = 8;

template <std::size_t MaxOrder = 32>
class TaxelTexture {
 public:
  /// config applies to every model; model i is seeded config.seed + i.
  /// @throws std::invalid_argument for no model set, more than
  ///         max_taxel_models, an id in the map past the last model set,
  ///         or a set HattTexture refuses.
  TaxelTexture(IndexMap taxels, const std::vector<texture::HattModelSet>& sets, const texture::HattConfig& config)
      : taxels_(std::move(taxels)) {
    if (sets.empty()) throw std::invalid_argument("TaxelTexture: no HaTT model set");
    if (sets.size() > max_taxel_models)
      throw std::invalid_argument("TaxelTexture: " + std::to_string(sets.size()) + " model sets, at most " +
                                  std::to_string(max_taxel_models));
    if (taxels_.largest() >= sets.size())
      throw std::invalid_argument("TaxelTexture: the taxel map names model " + std::to_string(taxels_.largest()) +
                                  " but there are " + std::to_string(sets.size()) + " model sets (0-based ids)");
    models_.reserve(sets.size());
    for (std::size_t i = 0; i < sets.size(); ++i) {
      texture::HattConfig c = config;
      c.seed = config.seed + static_cast<std::uint32_t>(i);
      models_.emplace_back(sets[i], c);
    }
  }

  /// sum_i w_i F_i [N], w_i the bilinear weight of model i's texels around
  /// the probe's surface_uv; zero for a non-finite uv.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    std::uint32_t ids[4];
    double weights[4];
    const bool located = taxels_.around(probe.surface_uv, ids, weights);
    std::array<double, max_taxel_models> w{};
    if (located)
      for (int k = 0; k < 4; ++k)
        w[ids[k]] += weights[k];  // ids < models_.size() (checked at construction)
    glm::dvec3 f{0.0};
    for (std::size_t i = 0; i < models_.size(); ++i) {
      const glm::dvec3 fi = models_[i].force(probe);  // every filter runs: none starts cold at a border
      f += w[i] * fi;
    }
    last_weights_ = w;
    return located && is_finite(f) ? f : glm::dvec3{0.0};
  }

  void reset() noexcept {
    for (auto& m : models_)
      m.reset();
  }

  /// Each model's weight in the last force() call.
  [[nodiscard]] const std::array<double, max_taxel_models>& last_weights() const noexcept { return last_weights_; }
  [[nodiscard]] std::size_t model_count() const noexcept { return models_.size(); }

 private:
  IndexMap taxels_;
  std::vector<texture::HattTexture<MaxOrder>> models_;
  std::array<double, max_taxel_models> last_weights_{};
};

}  // namespace hapticfield::material

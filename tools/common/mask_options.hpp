#pragma once
/// @file mask_options.hpp
/// --mask, --size and --border: the mask of the tools that feel a picture or
/// a video with the tangible-images method (tangible_image, tangible_video).

#include <stdexcept>
#include <string>

#include "cli.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/mask.hpp"
#include "hapticfield/kernels/tangible_image.hpp"

namespace hapticfield::cli {

/// The mask flags as given; apply() puts them into a TangibleConfig.
class MaskOptions {
 public:
  /// Takes the current token when it is --mask, --size or --border (true);
  /// leaves any other (false).
  bool take(Parser& p) {
    if (p.is("--mask")) {
      mask_ = p.named("mask", mask_kinds);
    } else if (p.is("--size")) {
      size_ = static_cast<int>(p.integer(1, 1000));
      size_given_ = true;
    } else if (p.is("--border")) {
      border_ = p.named("border", border_kinds);
    } else {
      return false;
    }
    return true;
  }

  /// `config` with the mask, border and size given; without --size the
  /// mask's own default size (a fixed-size mask its only size).
  /// @throws UsageError "--size: ..." when the size does not suit the mask.
  [[nodiscard]] TangibleConfig apply(TangibleConfig config) const {
    config.mask = mask_;
    config.border = border_;
    config.size = size_given_ ? size_ : default_mask_size(mask_);
    try {
      validate_mask_size(config.mask, config.size);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--size: ") + e.what());
    }
    return config;
  }

 private:
  MaskKind mask_{TangibleConfig{}.mask};
  Border border_{TangibleConfig{}.border};
  int size_{TangibleConfig{}.size};
  bool size_given_{false};
};

}  // namespace hapticfield::cli

#pragma once
/// @file mask.hpp
/// Force masks of the tangible-images method (Vasudevan & Manivannan 2008):
/// a pair of m x m weight tables (x and y) correlated with the inverted
/// image around the HIP. Weights are oriented so that the sum points toward
/// darker pixels: x weights grow to the right, y weights grow downward.
///
/// The size is a template parameter (`Mask<17>`: std::array storage, fixed
/// at compile time) or `dynamic_size` (`Mask<>`: chosen at run time, for
/// command-line tools); both are built by the same factories.

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "hapticfield/image/gray_image.hpp"

namespace hapticfield {

/// Mask families of the paper (Prewitt) and the alternatives it names.
enum class MaskKind {
  prewitt,   ///< x weight = column - centre in every row; any odd size 3..129
  sobel,     ///< binomial smoothing x derivative (OpenCV's Sobel); odd 3..31
  scharr,    ///< Scharr's rotation-optimised 3 x 3
  roberts,   ///< Roberts cross (2 x 2), its diagonals rotated onto x and y
  gaussian,  ///< first derivative of a Gaussian (sigma [px]); odd 3..129
  emboss,    ///< sign mask: right half minus left half (a block emboss); odd 3..129
};

/// Every mask kind, in the order the tools list them.
inline constexpr std::array<MaskKind, 6> mask_kinds{MaskKind::prewitt, MaskKind::sobel,    MaskKind::scharr,
                                                    MaskKind::roberts, MaskKind::gaussian, MaskKind::emboss};

/// The size a mask takes when none is given [px]: a fixed-size mask's only
/// size (Roberts 2, Scharr 3), Sobel's smallest aperture (3), else 17.
[[nodiscard]] constexpr int default_mask_size(MaskKind kind) noexcept {
  switch (kind) {
    case MaskKind::roberts:
      return 2;
    case MaskKind::scharr:
    case MaskKind::sobel:
      return 3;
    default:
      return 17;
  }
}

/// Template argument for a mask size chosen at run time.
inline constexpr int dynamic_size = 0;
inline constexpr int min_mask_size = 3;    ///< smallest odd mask [px]
inline constexpr int max_mask_size = 129;  ///< largest mask [px]
inline constexpr int max_sobel_size = 31;  ///< largest Sobel aperture (as OpenCV) [px]
/// Smallest Gaussian-derivative sigma [px]. Below it the off-centre weights
/// shrink toward underflow (every one is 0 for sigma <= 0.026 px, and the
/// mask would divide by a zero step response); at 0.05 px the weight one
/// pixel off centre is exp(-200) ~ 1e-87, still a normal double.
inline constexpr double min_gaussian_sigma = 0.05;

namespace detail {
/// A number as "%g" prints it (0.05, 1e-300), for error messages.
[[nodiscard]] inline std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
}  // namespace detail

/// Name of a mask kind as the command-line tools spell it.
[[nodiscard]] constexpr const char* to_string(MaskKind kind) noexcept {
  switch (kind) {
    case MaskKind::prewitt:
      return "prewitt";
    case MaskKind::sobel:
      return "sobel";
    case MaskKind::scharr:
      return "scharr";
    case MaskKind::roberts:
      return "roberts";
    case MaskKind::gaussian:
      return "gauss";
    case MaskKind::emboss:
      return "emboss";
  }
  return "?";
}

/// Checks that `size` is allowed for `kind`.
/// @throws std::invalid_argument naming the kind and the allowed sizes.
inline void validate_mask_size(MaskKind kind, int size) {
  const std::string name = to_string(kind);
  const auto fail = [&](const std::string& allowed) {
    throw std::invalid_argument("mask " + name + ": size " + std::to_string(size) + " px is not allowed (" + allowed +
                                ")");
  };
  switch (kind) {
    case MaskKind::scharr:
      if (size != 3) fail("Scharr is 3 x 3 only");
      return;
    case MaskKind::roberts:
      if (size != 2) fail("Roberts is 2 x 2 only");
      return;
    case MaskKind::sobel:
      if (size < min_mask_size || size > max_sobel_size || size % 2 == 0) fail("odd, 3 to 31");
      return;
    default:
      if (size < min_mask_size || size > max_mask_size || size % 2 == 0) fail("odd, 3 to 129");
  }
}

/// A pair of x / y weight tables of size x size, anchored at (size / 2,
/// size / 2) as OpenCV anchors kernels.
template <int Size = dynamic_size>
requires(Size == dynamic_size || (Size >= 2 && Size <= max_mask_size)) class Mask {
  using Storage = std::conditional_t<Size == dynamic_size, std::vector<double>, std::array<double, Size * Size>>;

 public:
  /// Prewitt as in the paper: x weight = column - centre in every row.
  [[nodiscard]] static Mask prewitt(int size = Size) {
    return build(MaskKind::prewitt, size, [](int, int c, int a) { return double(c - a); });
  }

  /// Sobel of any odd aperture up to 31: binomial smoothing across the
  /// derivative direction, binomial-smoothed central difference along it
  /// (the kernels of OpenCV's getDerivKernels).
  [[nodiscard]] static Mask sobel(int size = Size) {
    validate_mask_size(MaskKind::sobel, size);
    std::vector<double> smooth{1.0};
    for (int i = 1; i < size; ++i)
      smooth = convolve(smooth, {1.0, 1.0});
    std::vector<double> derivative{1.0};
    for (int i = 1; i < size - 1; ++i)
      derivative = convolve(derivative, {1.0, 1.0});
    derivative = convolve(derivative, {-1.0, 1.0});
    return build(MaskKind::sobel, size, [&](int r, int c, int) { return smooth[r] * derivative[c]; });
  }

  /// Scharr 3 x 3: smoothing [3 10 3], derivative [-1 0 1].
  [[nodiscard]] static Mask scharr(int size = Size) {
    constexpr double smooth[3] = {3.0, 10.0, 3.0};
    return build(MaskKind::scharr, size, [&](int r, int c, int) { return smooth[r % 3] * (c - 1); });  // size is 3
  }

  /// Roberts cross d1 = I(1,1) - I(0,0), d2 = I(1,0) - I(0,1), rotated from
  /// the diagonals onto the image axes: x = (d1 - d2) / 2, y = (d1 + d2) / 2.
  [[nodiscard]] static Mask roberts(int size = Size) {
    return build(MaskKind::roberts, size, [](int, int c, int) { return c == 1 ? 0.5 : -0.5; });
  }

  /// First derivative of a Gaussian of standard deviation sigma [px]:
  /// x weight = (c - centre) exp(-((c - centre)^2 + (r - centre)^2) / (2 sigma^2)).
  /// @throws std::invalid_argument for a sigma that is not finite or is below
  ///         min_gaussian_sigma (the message gives the allowed range).
  [[nodiscard]] static Mask gaussian(double sigma, int size = Size) {
    if (!std::isfinite(sigma) || sigma < min_gaussian_sigma)
      throw std::invalid_argument(
          "mask gauss: sigma must be finite and at least " + detail::short_number(min_gaussian_sigma) +
          " px (smaller sigmas make every off-centre weight underflow to 0), got " + detail::short_number(sigma));
    const double two_sigma2 = 2.0 * sigma * sigma;
    return build(MaskKind::gaussian, size, [&](int r, int c, int a) {
      const double dc = c - a;
      const double dr = r - a;
      return dc * std::exp(-(dc * dc + dr * dr) / two_sigma2);
    });
  }

  /// Block emboss: +1 right of the centre column, -1 left of it, 0 on it.
  [[nodiscard]] static Mask emboss(int size = Size) {
    return build(MaskKind::emboss, size, [](int, int c, int a) { return c > a ? 1.0 : (c < a ? -1.0 : 0.0); });
  }

  /// Any kind; sigma [px] is used by MaskKind::gaussian only (<= 0 picks
  /// size / 6, so the mask spans +-3 sigma).
  [[nodiscard]] static Mask make(MaskKind kind, int size = Size, double sigma = 0.0) {
    switch (kind) {
      case MaskKind::prewitt:
        return prewitt(size);
      case MaskKind::sobel:
        return sobel(size);
      case MaskKind::scharr:
        return scharr(size);
      case MaskKind::roberts:
        return roberts(size);
      case MaskKind::gaussian:
        return gaussian(sigma > 0.0 ? sigma : size / 6.0, size);
      case MaskKind::emboss:
        return emboss(size);
    }
    throw std::invalid_argument("mask: unknown kind");
  }

  [[nodiscard]] MaskKind kind() const noexcept { return kind_; }
  [[nodiscard]] int size() const noexcept { return size_; }
  /// Row and column of the weight that sits on the HIP's pixel.
  [[nodiscard]] int anchor() const noexcept { return size_ / 2; }
  /// x weight at (row, column) of the mask.
  [[nodiscard]] double x(int row, int col) const noexcept { return x_[row * size_ + col]; }
  /// y weight at (row, column) of the mask: the transpose of x.
  [[nodiscard]] double y(int row, int col) const noexcept { return x_[col * size_ + row]; }
  [[nodiscard]] const Storage& x_weights() const noexcept { return x_; }

  /// Response to an ideal black/white step edge across the mask centre on the
  /// inverted image: 255 times the sum of the positive x weights. Dividing by
  /// it makes that edge a force of magnitude 1 toward black. Every factory
  /// guarantees it is finite and positive.
  [[nodiscard]] double step_response() const noexcept { return step_response_; }

 private:
  template <class Weight>
  static Mask build(MaskKind kind, int size, Weight&& weight) {
    if constexpr (Size != dynamic_size) {
      if (size != Size)
        throw std::invalid_argument("mask: size " + std::to_string(size) + " differs from the compile-time size " +
                                    std::to_string(Size));
    }
    validate_mask_size(kind, size);
    Mask mask;
    mask.kind_ = kind;
    mask.size_ = size;
    if constexpr (Size == dynamic_size) mask.x_.assign(static_cast<std::size_t>(size) * size, 0.0);
    const int a = size / 2;
    double positive = 0.0;
    bool finite = true;
    for (int r = 0; r < size; ++r) {
      for (int c = 0; c < size; ++c) {
        const double w = weight(r, c, a);
        mask.x_[r * size + c] = w;
        finite = finite && std::isfinite(w);
        if (w > 0.0) positive += w;
      }
    }
    mask.step_response_ = gray_full_scale * positive;
    // A mask whose positive weights sum to 0 (all underflowed) or overflow
    // would normalise by 0 or infinity: NaN forces. Refuse it here.
    if (!finite || !std::isnormal(mask.step_response_) || !std::isnormal(1.0 / mask.step_response_))
      throw std::invalid_argument(std::string("mask ") + to_string(kind) + " " + std::to_string(size) + " x " +
                                  std::to_string(size) +
                                  ": the weights degenerate (non-finite, or the positive weights sum to " +
                                  std::to_string(positive) + "); no force can be normalised");
    return mask;
  }

  static std::vector<double> convolve(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> out(a.size() + b.size() - 1, 0.0);
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < b.size(); ++j)
        out[i + j] += a[i] * b[j];
    return out;
  }

  Mask() = default;

  Storage x_{};
  int size_ = Size;
  MaskKind kind_ = MaskKind::prewitt;
  double step_response_ = 1.0;
};

}  // namespace hapticfield

#include "organ_section.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace hysim::tools {
namespace {

using Rgb = std::array<std::uint8_t, 3>;

Rgb colourAt(const engine::OrganSpec& organ, const std::vector<engine::PlacedMyoma>& placed, const Eigen::Vector3d& p) {
  const int label = engine::organLabel(organ, placed, p);
  const Eigen::Vector3d& c = organ.uterus.cavity_semi_axes_mm;
  Rgb rgb{255, 255, 255};  // outside
  if (label == engine::kWallLabel) rgb = {214, 120, 128};
  else if (label >= engine::kFirstMyomaLabel) rgb = {238, 224, 180};
  else if ((p.array() / c.array()).matrix().squaredNorm() < 1.0 ||
           (p.z() < 0.0 && std::hypot(p.x(), p.y()) < organ.uterus.canal_radius_mm))
    rgb = {170, 205, 235};  // distension fluid in the cavity and the canal
  if (label != 0 && engine::organSizeAt(organ, placed, p) <= organ.mesh.fine_mm) {
    for (auto& v : rgb) v = static_cast<std::uint8_t>(v * 0.8);
  }
  return rgb;
}

}  // namespace

render::Image drawOrganSection(const engine::OrganSpec& organ, int width) {
  const std::vector<engine::PlacedMyoma> placed = engine::placeMyomas(organ);
  // Horizontal: towards the first myoma in the xy plane (anterior without one); vertical: z.
  Eigen::Vector3d across = Eigen::Vector3d::UnitY();
  if (!placed.empty()) {
    const Eigen::Vector3d d(placed[0].centre.x(), placed[0].centre.y(), 0.0);
    if (d.norm() > 1e-6) across = d.normalized();
  }
  const double half = engine::organBoundingRadius(organ, placed);
  const int height = width;
  render::Image image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double u = (2.0 * (x + 0.5) / width - 1.0) * half, v = (1.0 - 2.0 * (y + 0.5) / height) * half;
      const Eigen::Vector3d p = u * across + v * Eigen::Vector3d::UnitZ();
      const Rgb rgb = colourAt(organ, placed, p);
      std::uint8_t* px = image.pixel(x, y);
      px[0] = rgb[0];
      px[1] = rgb[1];
      px[2] = rgb[2];
      px[3] = 255;
    }
  }
  return image;
}

}  // namespace hysim::tools

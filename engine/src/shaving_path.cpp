#include "hysim/engine/shaving_path.hpp"

#include <algorithm>
#include <cmath>

namespace hysim::engine {
namespace {

using Eigen::Vector3d;

// The loop's geometry relative to the scope (scene.hpp's ContactSettings).
struct Scope {
  Vector3d pivot;
  Vector3d world_up;    // towards the cavity from the myoma's base: the loop hangs away from it
  double reach_mm = 12.0;
  double below_mm = 6.5;  // the loop's lowest point below the axis: drop + loop radius
  double min_tip_mm = 8.0;
};

// world_up made perpendicular to the axis; where the two are (nearly) parallel, as for a
// fundal myoma straight ahead, anterior (or left) instead.
Vector3d upFor(const Vector3d& axis, const Vector3d& world_up) {
  for (const Vector3d& u : {world_up, Vector3d(Vector3d::UnitY()), Vector3d(Vector3d::UnitX())}) {
    const Vector3d perp = u - u.dot(axis) * axis;
    if (perp.norm() > 0.2) return perp.normalized();
  }
  return Vector3d::UnitX();
}

// The axis through the pivot that puts the loop's lowest point on `target`.
Vector3d aim(const Scope& s, const Vector3d& target) {
  Vector3d axis = (target - s.pivot).normalized();
  for (int i = 0; i < 50; ++i) axis = (target - s.pivot + s.below_mm * upFor(axis, s.world_up)).normalized();
  return axis;
}

// How far beyond the tip the loop's centre sits when its lowest point is on `target`.
double alongTo(const Scope& s, const Vector3d& axis, const Vector3d& target) {
  return (target + s.below_mm * upFor(axis, s.world_up) - s.pivot).norm();
}

haptics::Keyframe key(double t, const Scope& s, const Vector3d& axis, double tip_mm, double ext, bool pedal) {
  haptics::Keyframe k;
  k.time_s = t;
  k.tip = s.pivot + tip_mm * axis;
  k.axis = axis;
  k.up = upFor(axis, s.world_up);
  k.extension_mm = ext;
  k.pedal = pedal;
  return k;
}

// What a pass must keep from the serosa: the outer ellipsoid, the wall's normal under the
// myoma, and the distance.
struct SerosaGuard {
  Vector3d outer;
  Vector3d normal;
  double keep_mm = 0.0;
};


// The loop's lowest point with the scope along `axis`, the tip `tip_mm` in, extended `ext`.
Vector3d loopBottom(const Scope& s, const Vector3d& axis, double tip_mm, double ext) {
  return s.pivot + (tip_mm + s.reach_mm + ext) * axis - s.below_mm * upFor(axis, s.world_up);
}

// One pass: loop bottom through `target` (drawn back over `half_len` mm either side along the
// axis, less where an end of the draw would come too near the serosa), entering and leaving
// at `lifted`.
// The loop is pushed out at `approach` (above a myoma on a stalk, which it would otherwise
// shove away; else `lifted`).
void addPass(std::vector<haptics::Keyframe>& out, double& t, const Scope& s, const Vector3d& target,
             const Vector3d& lifted, const Vector3d& approach, double half_len, const SerosaGuard& g) {
  constexpr double kMaxExt = 17.0, kMidExt = 8.5, kStep = 0.5;
  const Vector3d cut = aim(s, target), lift = aim(s, lifted), over = aim(s, approach);
  const double tip = std::max(s.min_tip_mm, alongTo(s, cut, target) - s.reach_mm - kMidExt);
  const double mid = alongTo(s, cut, target) - s.reach_mm - tip;
  double far = std::clamp(mid + half_len + 4.0, 0.0, kMaxExt), near = std::clamp(mid - half_len - 4.0, 0.0, far);
  while (far > std::max(mid, 0.0) && ellipsoidExitMm(loopBottom(s, cut, tip, far), g.normal, g.outer) < g.keep_mm) far -= kStep;
  while (near < std::min(mid, far) && ellipsoidExitMm(loopBottom(s, cut, tip, near), g.normal, g.outer) < g.keep_mm) near += kStep;
  far = std::max(far, 0.0);
  near = std::clamp(near, 0.0, far);
  out.push_back(key(t + 0.20, s, over, tip, 0.0, false));
  out.push_back(key(t + 0.60, s, over, tip, far, false));
  out.push_back(key(t + 0.65, s, over, tip, far, true));
  out.push_back(key(t + 0.90, s, cut, tip, far, true));
  out.push_back(key(t + 1.75, s, cut, tip, near, true));
  out.push_back(key(t + 1.95, s, lift, tip, 0.0, true));
  out.push_back(key(t + 2.00, s, lift, tip, 0.0, false));
  t += 2.0;
}


// The target raised towards the cavity until the serosa under it is at least `keep` away.
Vector3d keepOffSerosa(const Vector3d& target, const Vector3d& normal, const Vector3d& outer, double keep) {
  const double below = ellipsoidExitMm(target, normal, outer);
  return below < keep ? Vector3d(target - (keep - below) * normal) : target;
}

bool reachable(const std::string& figo) {
  return figo == "0" || figo == "1" || figo == "2" || figo == "3" || figo == "4" || figo == "2-5";
}

// Half the width the loop clears on a level `s` mm from the myoma's centre along the normal.
double levelHalfWidth(const PlacedMyoma& m, double s) {
  if (std::abs(s) < m.radius_mm) return std::sqrt(m.radius_mm * m.radius_mm - s * s);
  return s < 0.0 ? 0.7 * m.radius_mm : m.stalk_radius_mm;  // the roof over it, or its stalk
}

// Levels from the tissue's cavity side to the myoma's base, passes side to side on each,
// rows along the scope where one draw of the loop (15 mm) cannot cover the myoma.
void planMyoma(std::vector<haptics::Keyframe>& out, double& t, const OrganSpec& organ, const MyomaSpec& spec,
               const PlacedMyoma& m, Scope s, double margin, const ShavingPlan& plan) {
  s.world_up = -m.normal;
  const double offset = myomaOffsetMm(spec, organ.uterus);
  const Vector3d outer = outerSemiAxes(organ.uterus);
  const double toSerosa = ellipsoidExitMm(m.centre, m.normal, outer);  // under the myoma's centre
  const SerosaGuard guard{outer, m.normal, margin + plan.serosa_safety_mm};
  const double top = -std::max(m.radius_mm, offset);  // the endometrium over an intramural myoma
  double bottom = std::min(m.radius_mm - 1.0, toSerosa - margin - plan.serosa_safety_mm);
  if (m.stalk && spec.figo == "0") bottom = 0.5 * (m.radius_mm + (m.base - m.centre).norm());
  Vector3d along = m.centre - s.pivot;
  along = (along - along.dot(m.normal) * m.normal).normalized();
  Vector3d side = m.normal.cross(along);
  if (side.norm() < 1e-6) side = Vector3d::UnitX();
  side.normalize();
  // A large myoma is taken in thicker slices and wider strips (up to the loop's reach).
  const double step = std::max(plan.level_step_mm, m.radius_mm / 5.0);
  const double spacing = std::max(plan.pass_spacing_mm, m.radius_mm / 3.0);
  // Levels `step` apart from just under the top, and one at the deepest allowed.
  std::vector<double> levels;
  for (double lv = top + 1.5; lv <= bottom + 1e-9; lv += step) levels.push_back(lv);
  if (levels.empty() || levels.back() < bottom - 0.5) levels.push_back(bottom);
  for (const double lv : levels) {
    const double hw = levelHalfWidth(m, lv);
    const double reach = std::max(hw - plan.edge_mm, 0.0);
    const int n = std::max(1, static_cast<int>(std::ceil(2.0 * reach / spacing)) + 1);
    const int rows = std::max(1, static_cast<int>(std::ceil((2.0 * hw + 4.0) / 15.0)));
    for (int row = 0; row < rows; ++row) {
      const double off = rows == 1 ? 0.0 : -hw + 2.0 * hw * (row + 0.5) / rows;
      for (int i = 0; i < n; ++i) {
        const double x = n == 1 ? 0.0 : -reach + 2.0 * reach * i / (n - 1);
        const Vector3d target = keepOffSerosa(m.centre + lv * m.normal + x * side + off * along, m.normal, outer,
                                              margin + plan.serosa_safety_mm);
        const Vector3d lifted = target - plan.lift_mm * m.normal;
        const Vector3d approach = spec.figo == "0" ? Vector3d(target + (top - 3.0 - lv) * m.normal) : lifted;
        addPass(out, t, s, target, lifted, approach, hw / rows, guard);
      }
    }
  }
}

}  // namespace

Vector3d scopePivot(const UterusSpec& u) { return {0.0, 0.0, -(u.cavity_semi_axes_mm.z() + 2.0 * u.wall_mm / 3.0)}; }

double scopeTipMm(const UterusSpec& u) { return 2.0 * u.wall_mm / 3.0 + 8.0; }

std::vector<haptics::Keyframe> planShavingPath(const OrganSpec& organ, const ContactSettings& contact,
                                               double perforation_margin_mm, const ShavingPlan& plan) {
  std::vector<haptics::Keyframe> out;
  const std::vector<PlacedMyoma> placed = placeMyomas(organ);
  Scope s;
  s.pivot = scopePivot(organ.uterus);
  s.reach_mm = contact.loop_reach_mm;
  s.below_mm = contact.loop_drop_mm + contact.loop_radius_mm;
  s.min_tip_mm = 2.0 * organ.uterus.wall_mm / 3.0 + 2.0;
  s.world_up = Vector3d::UnitY();
  const Vector3d rest = s.pivot + scopeTipMm(organ.uterus) * Vector3d::UnitZ();
  double t = 0.0;
  out.push_back(key(0.0, s, Vector3d::UnitZ(), (rest - s.pivot).norm(), 0.0, false));
  for (size_t k = 0; k < placed.size(); ++k) {
    if (!reachable(organ.myomas[k].figo)) continue;
    planMyoma(out, t, organ, organ.myomas[k], placed[k], s, perforation_margin_mm, plan);
  }
  if (out.size() == 1) return {};
  // Rest poses rolled as the first and last passes, so the scope does not turn on the way.
  out.front().up = out[1].up;
  out.push_back(key(t + 0.5, s, Vector3d::UnitZ(), (rest - s.pivot).norm(), 0.0, false));
  out.back().up = out[out.size() - 2].up;
  return out;
}

}  // namespace hysim::engine

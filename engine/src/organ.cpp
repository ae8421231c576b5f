#include "hysim/engine/organ.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hysim::engine {
namespace {

constexpr double kPi = 3.14159265358979323846;

double ellipsoidLevel(const Eigen::Vector3d& p, const Eigen::Vector3d& semi) {
  return (p.array() / semi.array()).matrix().squaredNorm();
}


// The endometrium point a myoma sits on (the cavity ellipsoid along the wall's direction).
Eigen::Vector3d basePoint(const MyomaSpec& m, const UterusSpec& u) {
  const Eigen::Vector3d& s = u.cavity_semi_axes_mm;
  const double a = m.angle_deg * kPi / 180.0;
  if (m.wall == MyomaWall::Fundal) {
    const Eigen::Vector3d d(0.0, std::sin(a), std::cos(a));
    return d * ellipsoidExitMm(Eigen::Vector3d::Zero(), d, s);
  }
  double azimuth = 0.0;  // from +x (the patient's left) towards +y (anterior)
  switch (m.wall) {
    case MyomaWall::Left: azimuth = 0.0; break;
    case MyomaWall::Anterior: azimuth = 90.0; break;
    case MyomaWall::Right: azimuth = 180.0; break;
    default: azimuth = 270.0; break;
  }
  const double phi = azimuth * kPi / 180.0 + a;
  const Eigen::Vector3d origin(0.0, 0.0, m.height * s.z());
  return origin + Eigen::Vector3d(std::cos(phi), std::sin(phi), 0.0) *
                      ellipsoidExitMm(origin, Eigen::Vector3d(std::cos(phi), std::sin(phi), 0.0), s);
}

double stalkLength(double r) { return std::max(2.0, 0.4 * r); }

// Distance from p to the segment [a, b].
double segmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

// Distance from p to myoma k's surface (0 inside it or its stalk).
double myomaDistance(const PlacedMyoma& m, const Eigen::Vector3d& p) {
  double d = std::max((p - m.centre).norm() - m.radius_mm, 0.0);
  if (m.stalk) d = std::min(d, std::max(segmentDistance(p, m.stalk_from, m.stalk_to) - m.stalk_radius_mm, 0.0));
  return d;
}

bool insideMyoma(const PlacedMyoma& m, const Eigen::Vector3d& p) {
  if ((p - m.centre).squaredNorm() < m.radius_mm * m.radius_mm) return true;
  return m.stalk && segmentDistance(p, m.stalk_from, m.stalk_to) < m.stalk_radius_mm;
}

// Polynomial smooth minimum: min(a, b) with the corner rounded over about k mm.
double smoothMin(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - 0.25 * h * h * k;
}

// Approximate signed distance (mm, < 0 inside) to an ellipsoid.
double ellipsoidDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& semi) {
  return (std::sqrt(ellipsoidLevel(p, semi)) - 1.0) * semi.minCoeff();
}

// Signed distance-like value of the wall (< 0 inside): the outer ellipsoid minus the cavity and
// the cervical canal. Where the canal meets the cavity and the outer surface the edges are
// rounded over 2 mm: a sharp crease there leaves flat tets that no mesh optimiser can mend.
double wallValue(const UterusSpec& u, const Eigen::Vector3d& p) {
  constexpr double kRound = 2.0;
  const Eigen::Vector3d& s = u.cavity_semi_axes_mm;
  // The canal ends inside the cavity, where the cavity is at least 1.5 mm wider than it.
  const double fit = std::min((u.canal_radius_mm + 1.5) / std::min(s.x(), s.y()), 0.95);
  const double top = -s.z() * std::sqrt(1.0 - fit * fit);
  const double canal = std::max(std::hypot(p.x(), p.y()) - u.canal_radius_mm, p.z() - top);
  const double hollow = smoothMin(ellipsoidDistance(p, s), canal, kRound);
  return -smoothMin(-ellipsoidDistance(p, outerSemiAxes(u)), hollow, kRound);
}

// Shares of a myoma's sphere in the cavity, in the wall and outside the uterus (a lattice of
// points; 1/20 of the diameter apart).
struct Shares {
  double cavity = 0.0, wall = 0.0, outside = 0.0;
};

Shares sharesOf(const PlacedMyoma& m, const UterusSpec& u) {
  const Eigen::Vector3d outer = outerSemiAxes(u);
  constexpr int kN = 20;
  int inCavity = 0, inWall = 0, out = 0;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      for (int k = 0; k < kN; ++k) {
        const Eigen::Vector3d q = Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * (2.0 / kN) - Eigen::Vector3d::Ones();
        if (q.squaredNorm() > 1.0) continue;
        const Eigen::Vector3d p = m.centre + m.radius_mm * q;
        if (ellipsoidLevel(p, u.cavity_semi_axes_mm) < 1.0) ++inCavity;
        else if (ellipsoidLevel(p, outer) < 1.0) ++inWall;
        else ++out;
      }
    }
  }
  const double n = std::max(inCavity + inWall + out, 1);
  return {inCavity / n, inWall / n, out / n};
}

// The wall's thickness under a myoma, along the cavity's normal.
double wallThicknessAt(const PlacedMyoma& m, const UterusSpec& u) {
  return ellipsoidExitMm(m.base, m.normal, outerSemiAxes(u));
}

std::string typeMismatch(const std::string& figo, const Shares& s, double gapCavity, double gapSerosa) {
  constexpr double kSome = 0.005;
  if (figo == "0" && s.cavity < 1.0 - kSome) return "a FIGO 0 myoma must lie wholly in the cavity (on its stalk)";
  if (figo == "1" && !(s.cavity > 0.5 && s.wall > kSome)) return "a FIGO 1 myoma must be less than half intramural";
  if (figo == "2" && !(s.wall >= 0.5 && s.cavity > kSome && s.outside < kSome)) {
    return "a FIGO 2 myoma must be at least half intramural and reach into the cavity";
  }
  if (figo == "3" && !(s.cavity < kSome && s.outside < kSome && gapCavity <= 1.5)) {
    return "a FIGO 3 myoma must be intramural and touch the endometrium (within 1.5 mm)";
  }
  if (figo == "4" && !(s.cavity < kSome && s.outside < kSome && gapCavity > 1.5 && gapSerosa > 1.5)) {
    return "a FIGO 4 myoma must be intramural, more than 1.5 mm from the endometrium and the serosa";
  }
  if (figo == "2-5" && !(s.cavity > kSome && s.outside > kSome)) return "a FIGO 2-5 myoma must reach both the cavity and the serosa";
  if (figo == "5" && !(s.cavity < kSome && s.outside > kSome && s.outside < 0.5)) {
    return "a FIGO 5 myoma must be subserosal and at least half intramural";
  }
  if (figo == "6" && !(s.outside >= 0.5 && s.wall > kSome)) return "a FIGO 6 myoma must be subserosal and less than half intramural";
  if (figo == "7" && s.outside < 1.0 - kSome) return "a FIGO 7 myoma must lie wholly outside the wall (on its stalk)";
  return "";
}

void checkMyoma(const OrganSpec& organ, const PlacedMyoma& p, int k, std::vector<OrganProblem>& out) {
  const MyomaSpec& m = organ.myomas[static_cast<size_t>(k)];
  const Shares s = sharesOf(p, organ.uterus);
  const double offset = std::isnan(m.offset_mm) ? myomaOffsetMm(m, organ.uterus) : m.offset_mm;
  const double gapCavity = offset - p.radius_mm;
  const double gapSerosa = wallThicknessAt(p, organ.uterus) - offset - p.radius_mm;
  const bool stalked = m.figo == "0" || m.figo == "7";
  if (s.cavity < 0.005 && s.wall < 0.005 && !stalked) {
    out.push_back({k, "offset_mm", "the myoma lies outside the uterus"});
    return;
  }
  if (const std::string why = typeMismatch(m.figo, s, gapCavity, gapSerosa); !why.empty()) {
    out.push_back({k, std::isnan(m.offset_mm) ? "figo" : "offset_mm", why});
    return;
  }
  const bool cavitySide = m.figo == "1" || m.figo == "2" || m.figo == "3";
  if (cavitySide && gapSerosa < 2.0) {
    char text[160];
    std::snprintf(text, sizeof text, "the myoma comes %.1f mm from the serosa (at least 2 mm for FIGO %s; "
                  "a transmural one is 2-5)", gapSerosa, m.figo.c_str());
    out.push_back({k, "diameter_mm", text});
  }
  if (m.figo == "0") {
    // The myoma on its stalk must not reach the opposite wall.
    const Eigen::Vector3d tip = p.centre - p.normal * p.radius_mm;
    if (ellipsoidLevel(tip, organ.uterus.cavity_semi_axes_mm) > 1.0) {
      out.push_back({k, "diameter_mm", "the myoma on its stalk does not fit in the cavity"});
    }
  }
}

// Beyond this many tets an organ would take minutes to mesh and gigabytes to hold.
constexpr double kMaxOrganTets = 2e6;

// A regular tet of edge h has volume h^3 / 8.5; Delaunay meshes come out at about that.
double estimatedTets(const OrganSpec& organ) {
  constexpr double kPi3 = 4.18879020478639;  // 4 pi / 3
  const Eigen::Vector3d o = outerSemiAxes(organ.uterus), c = organ.uterus.cavity_semi_axes_mm;
  double fine = 0.0;
  for (const MyomaSpec& m : organ.myomas) fine += kPi3 * std::pow(0.5 * m.diameter_mm + organ.mesh.fine_band_mm, 3);
  const double wall = kPi3 * (o.prod() - c.prod());
  const double h = organ.mesh.fine_mm, H = organ.mesh.coarse_mm;
  return 8.5 * (fine / (h * h * h) + wall / (H * H * H));
}

}  // namespace

double ellipsoidExitMm(const Eigen::Vector3d& from, const Eigen::Vector3d& d, const Eigen::Vector3d& semi) {
  const Eigen::Vector3d a = (d.array() / semi.array()).matrix(), b = (from.array() / semi.array()).matrix();
  const double qa = a.squaredNorm(), qb = 2.0 * a.dot(b), qc = b.squaredNorm() - 1.0;
  return (-qb + std::sqrt(std::max(qb * qb - 4.0 * qa * qc, 0.0))) / (2.0 * qa);
}

Eigen::Vector3d outerSemiAxes(const UterusSpec& u) {
  return u.cavity_semi_axes_mm + Eigen::Vector3d::Constant(u.wall_mm);
}

double myomaOffsetMm(const MyomaSpec& m, const UterusSpec& u) {
  if (!std::isnan(m.offset_mm)) return m.offset_mm;
  const double r = 0.5 * m.diameter_mm, w = u.wall_mm;
  if (m.figo == "0") return -(r + stalkLength(r));
  if (m.figo == "1") return -0.25 * r;
  if (m.figo == "2") return 0.25 * r;
  if (m.figo == "3") return r + 0.5;
  if (m.figo == "4" || m.figo == "2-5") return 0.5 * w;
  if (m.figo == "5") return w - 0.25 * r;
  if (m.figo == "6") return w + 0.25 * r;
  return w + r + stalkLength(r);  // "7"
}

std::vector<PlacedMyoma> placeMyomas(const OrganSpec& organ) {
  std::vector<PlacedMyoma> placed;
  const Eigen::Vector3d& s = organ.uterus.cavity_semi_axes_mm;
  for (const MyomaSpec& m : organ.myomas) {
    PlacedMyoma p;
    p.base = basePoint(m, organ.uterus);
    p.normal = (p.base.array() / (s.array() * s.array())).matrix().normalized();
    p.radius_mm = 0.5 * m.diameter_mm;
    p.centre = p.base + p.normal * myomaOffsetMm(m, organ.uterus);
    if (m.figo == "0" || m.figo == "7") {
      p.stalk = true;
      p.stalk_radius_mm = std::max(1.5, 0.35 * p.radius_mm);
      // From 1 mm inside the wall (type 0) or 1 mm inside the serosa (type 7) to the centre.
      const double anchor = m.figo == "0" ? 1.0 : wallThicknessAt(p, organ.uterus) - 1.0;
      p.stalk_from = p.base + p.normal * anchor;
      p.stalk_to = p.centre;
    }
    placed.push_back(p);
  }
  return placed;
}

int organLabel(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed, const Eigen::Vector3d& p) {
  for (size_t k = 0; k < placed.size(); ++k) {
    if (insideMyoma(placed[k], p)) return kFirstMyomaLabel + static_cast<int>(k);
  }
  return wallValue(organ.uterus, p) < 0.0 ? kWallLabel : 0;
}

double organSizeAt(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed, const Eigen::Vector3d& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const PlacedMyoma& m : placed) d = std::min(d, myomaDistance(m, p));
  const OrganMeshSizes& s = organ.mesh;
  constexpr double kGrowthPerMm = 0.5;  // a gentle grading keeps neighbouring tets alike
  const double far = std::min(s.coarse_mm, 0.5 * organ.uterus.wall_mm);
  if (!(d > s.fine_band_mm)) return s.fine_mm;
  return std::min(s.fine_mm + kGrowthPerMm * (d - s.fine_band_mm), std::max(far, s.fine_mm));
}

double organBoundingRadius(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed) {
  double r = outerSemiAxes(organ.uterus).maxCoeff();
  for (const PlacedMyoma& m : placed) {
    r = std::max(r, m.centre.norm() + m.radius_mm);
    if (m.stalk) r = std::max(r, m.stalk_from.norm() + m.stalk_radius_mm);
  }
  return r + 2.0;
}

std::vector<OrganProblem> checkOrgan(const OrganSpec& organ) {
  std::vector<OrganProblem> out;
  const UterusSpec& u = organ.uterus;
  if (u.wall_mm < 2.0 * organ.mesh.coarse_mm) {
    char text[200];
    std::snprintf(text, sizeof text, "the wall (%.3g mm) is too thin for mesh.coarse_mm %.3g: it needs at least "
                  "two coarse edges across (lower coarse_mm to %.3g or less)", u.wall_mm, organ.mesh.coarse_mm,
                  0.5 * u.wall_mm);
    out.push_back({-1, "wall_mm", text});
  }
  if (organ.mesh.fine_mm > organ.mesh.coarse_mm) {
    out.push_back({-1, "fine_mm", "mesh.fine_mm must not be larger than mesh.coarse_mm"});
  }
  if (const double tets = estimatedTets(organ); tets > kMaxOrganTets) {
    char text[200];
    std::snprintf(text, sizeof text, "the organ would need about %.1f million tets at fine_mm %.3g (at most %.1f million):"
                  " raise fine_mm or lower fine_band_mm", tets / 1e6, organ.mesh.fine_mm, kMaxOrganTets / 1e6);
    out.push_back({-1, "fine_mm", text});
  }
  if (u.canal_radius_mm > 0.8 * std::min(u.cavity_semi_axes_mm.x(), u.cavity_semi_axes_mm.y())) {
    out.push_back({-1, "canal_radius_mm", "the canal is wider than the cavity"});
  }
  const std::vector<PlacedMyoma> placed = placeMyomas(organ);
  for (size_t k = 0; k < placed.size(); ++k) checkMyoma(organ, placed[k], static_cast<int>(k), out);
  for (size_t j = 0; j < placed.size(); ++j) {
    for (size_t k = 0; k < j; ++k) {
      const double gap = (placed[j].centre - placed[k].centre).norm() - placed[j].radius_mm - placed[k].radius_mm;
      if (gap < 1.0) {
        out.push_back({static_cast<int>(j), "wall",
                       "the myoma overlaps organ.myomas[" + std::to_string(k) + "] (or is within 1 mm of it)"});
      }
    }
  }
  return out;
}

std::vector<double> wallBehindMyomasMm(const OrganSpec& organ, const cutting::TetMesh& mesh) {
  const std::vector<PlacedMyoma> placed = placeMyomas(organ);
  const Eigen::Vector3d outer = outerSemiAxes(organ.uterus);
  std::vector<char> surface(static_cast<size_t>(mesh.numNodes()), 0);
  const cutting::Tris faces = cutting::boundaryFaces(mesh);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int c = 0; c < 3; ++c) surface[faces(f, c)] = 1;
  }
  std::vector<double> out;
  for (const PlacedMyoma& m : placed) {
    double thinnest = std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < mesh.numNodes(); ++i) {
      if (!surface[i]) continue;
      const Eigen::Vector3d x = mesh.X.row(i).transpose();
      const Eigen::Vector3d d = x - m.centre;
      if ((d - d.dot(m.normal) * m.normal).norm() > m.radius_mm) continue;  // outside the footprint
      if (ellipsoidLevel(x, outer) >= 1.0) continue;
      const double wall = ellipsoidExitMm(x, m.normal, outer);
      if (wall < 0.3) continue;  // a node of the serosa itself
      if (!(wall >= thinnest)) thinnest = wall;
    }
    out.push_back(thinnest);
  }
  return out;
}

std::string organKey(const OrganSpec& organ) {
  std::string key;
  char part[256];
  const UterusSpec& u = organ.uterus;
  std::snprintf(part, sizeof part, "uterus %.17g %.17g %.17g %.17g %.17g|mesh %.17g %.17g %.17g|",
                u.cavity_semi_axes_mm.x(), u.cavity_semi_axes_mm.y(), u.cavity_semi_axes_mm.z(), u.wall_mm,
                u.canal_radius_mm, organ.mesh.fine_mm, organ.mesh.coarse_mm, organ.mesh.fine_band_mm);
  key += part;
  for (const MyomaSpec& m : organ.myomas) {
    std::snprintf(part, sizeof part, "myoma %s %.17g %s %.17g %.17g %.17g|", m.figo.c_str(), m.diameter_mm,
                  wallName(m.wall).c_str(), m.angle_deg, m.height, myomaOffsetMm(m, u));
    key += part;
  }
  return key;
}

std::string wallName(MyomaWall w) {
  switch (w) {
    case MyomaWall::Anterior: return "anterior";
    case MyomaWall::Posterior: return "posterior";
    case MyomaWall::Left: return "left";
    case MyomaWall::Right: return "right";
    case MyomaWall::Fundal: return "fundal";
  }
  return "posterior";
}

}  // namespace hysim::engine

// The scene's `organ:` section: the uterus and its myomas as parameters (organ.hpp), checked
// here so that an organ that cannot be built is refused at load, naming the line and the key,
// before anything is meshed or cached.
#include "scene_reader.hpp"

namespace hysim::engine::scene_detail {
namespace {

double inRange(const Reader& r, const YAML::Node& n, const std::string& key, double lo, double hi) {
  const double v = r.number(n, key);
  if (v < lo || v > hi) {
    char text[160];
    std::snprintf(text, sizeof text, "'%s' must be between %g and %g, got ", key.c_str(), lo, hi);
    r.fail(n, text + n.Scalar());
  }
  return v;
}

void parseUterus(const Reader& r, const YAML::Node& n, UterusSpec& u) {
  r.checkKeys(n, "organ.uterus", {"cavity_semi_axes_mm", "wall_mm", "canal_radius_mm", "young_modulus_kpa",
                                  "anchored_depth_mm"});
  if (n["cavity_semi_axes_mm"]) {
    const YAML::Node a = n["cavity_semi_axes_mm"];
    u.cavity_semi_axes_mm = r.vec3(a, "cavity_semi_axes_mm");
    if ((u.cavity_semi_axes_mm.array() < 6.0).any() || (u.cavity_semi_axes_mm.array() > 60.0).any()) {
      r.fail(a, "'cavity_semi_axes_mm' must each be between 6 and 60");
    }
  }
  if (n["wall_mm"]) u.wall_mm = inRange(r, n["wall_mm"], "wall_mm", 3.0, 30.0);
  if (n["canal_radius_mm"]) u.canal_radius_mm = inRange(r, n["canal_radius_mm"], "canal_radius_mm", 1.0, 8.0);
  if (n["young_modulus_kpa"]) u.myometrium_kpa = inRange(r, n["young_modulus_kpa"], "young_modulus_kpa", 1.0, 1000.0);
  if (n["anchored_depth_mm"]) {
    u.anchored_depth_mm = inRange(r, n["anchored_depth_mm"], "anchored_depth_mm", 0.5, 0.5 * u.wall_mm);
  }
}

MyomaWall parseWall(const Reader& r, const YAML::Node& n) {
  const std::string w = r.string(n, "wall");
  if (w == "anterior") return MyomaWall::Anterior;
  if (w == "posterior") return MyomaWall::Posterior;
  if (w == "left") return MyomaWall::Left;
  if (w == "right") return MyomaWall::Right;
  if (w == "fundal") return MyomaWall::Fundal;
  r.fail(n, "'wall' must be anterior, posterior, left, right or fundal, got '" + w + "'");
}

MyomaSpec parseMyoma(const Reader& r, const YAML::Node& n) {
  r.checkKeys(n, "organ.myomas[]", {"figo", "diameter_mm", "wall", "angle_deg", "height", "young_modulus_kpa",
                                    "offset_mm"});
  MyomaSpec m;
  m.figo = r.string(r.require(n, "figo", "organ.myomas[]"), "figo");
  static const std::set<std::string> kTypes = {"0", "1", "2", "3", "4", "5", "6", "7", "2-5"};
  if (!kTypes.count(m.figo)) r.fail(n["figo"], "'figo' must be 0 to 7 or 2-5, got '" + m.figo + "'");
  m.diameter_mm = inRange(r, r.require(n, "diameter_mm", "organ.myomas[]"), "diameter_mm", 3.0, 60.0);
  m.wall = parseWall(r, r.require(n, "wall", "organ.myomas[]"));
  if (n["angle_deg"]) m.angle_deg = inRange(r, n["angle_deg"], "angle_deg", -180.0, 180.0);
  if (n["height"]) m.height = inRange(r, n["height"], "height", -0.8, 0.8);
  if (n["young_modulus_kpa"]) m.young_modulus_kpa = inRange(r, n["young_modulus_kpa"], "young_modulus_kpa", 1.0, 1000.0);
  if (n["offset_mm"]) m.offset_mm = inRange(r, n["offset_mm"], "offset_mm", -100.0, 100.0);
  return m;
}

void parseMeshSizes(const Reader& r, const YAML::Node& n, OrganMeshSizes& s) {
  r.checkKeys(n, "organ.mesh", {"fine_mm", "coarse_mm", "fine_band_mm"});
  if (n["fine_mm"]) s.fine_mm = inRange(r, n["fine_mm"], "fine_mm", 0.5, 5.0);
  if (n["coarse_mm"]) s.coarse_mm = inRange(r, n["coarse_mm"], "coarse_mm", s.fine_mm, 10.0);
  if (n["fine_band_mm"]) s.fine_band_mm = inRange(r, n["fine_band_mm"], "fine_band_mm", 0.0, 20.0);
}

// The node an organ problem points at: the myoma's key, else the myoma, else the section.
YAML::Node problemNode(const YAML::Node& organ, const OrganProblem& p) {
  if (p.myoma >= 0) {
    const YAML::Node m = organ["myomas"][static_cast<size_t>(p.myoma)];
    return m[p.key] ? m[p.key] : m;
  }
  // The mesh sizes' key when the scene gives it (a wall too thin for a coarse size asked).
  const YAML::Node mesh = organ["mesh"];
  if (p.key == "wall_mm" && mesh && mesh["coarse_mm"]) return mesh["coarse_mm"];
  if (mesh && mesh[p.key]) return mesh[p.key];
  const YAML::Node u = organ["uterus"];
  if (u && u[p.key]) return u[p.key];
  return u ? u : organ;
}

// Label 1 the wall, 2.. each myoma (all named "myoma": drawn pale, counted as resected).
void organMaterials(const OrganSpec& organ, std::vector<sim::Material>& materials) {
  sim::Material wall;
  wall.name = "myometrium";
  wall.label = kWallLabel;
  wall.young_modulus_pa = 1e3 * organ.uterus.myometrium_kpa;
  wall.density_g_mm3 = 1.05e-3;
  wall.stiffness_damping_s = 2.0e-5;
  materials.push_back(wall);
  for (size_t k = 0; k < organ.myomas.size(); ++k) {
    sim::Material m = wall;
    m.name = "myoma";
    m.label = kFirstMyomaLabel + static_cast<int>(k);
    m.young_modulus_pa = 1e3 * organ.myomas[k].young_modulus_kpa;
    m.density_g_mm3 = 1.10e-3;
    materials.push_back(m);
  }
}

}  // namespace

void parseOrgan(const Reader& r, const YAML::Node& n, Scene& scene) {
  r.checkKeys(n, "organ", {"uterus", "myomas", "mesh"});
  OrganSpec& organ = scene.organ;
  organ.given = true;
  if (n["uterus"]) parseUterus(r, n["uterus"], organ.uterus);
  if (n["mesh"]) parseMeshSizes(r, n["mesh"], organ.mesh);
  const YAML::Node list = r.require(n, "myomas", "organ");
  if (!list.IsSequence() || list.size() == 0 || list.size() > 8) r.fail(list, "'myomas' must be a list of 1 to 8 myomas");
  for (const auto& m : list) organ.myomas.push_back(parseMyoma(r, m));
  const std::vector<OrganProblem> problems = checkOrgan(organ);
  if (!problems.empty()) {
    const OrganProblem& p = problems.front();
    const bool sizes = p.key == "fine_mm" || p.key == "coarse_mm";
    const std::string who = p.myoma >= 0 ? "organ.myomas[" + std::to_string(p.myoma) + "]"
                                         : (sizes ? "organ.mesh" : "organ.uterus");
    r.fail(problemNode(n, p), who + "." + p.key + ": " + p.message);
  }
  organMaterials(organ, scene.materials);
  AnchorRegion held;
  held.kind = AnchorRegion::Kind::OutsideEllipsoid;
  held.b = outerSemiAxes(organ.uterus) - Eigen::Vector3d::Constant(organ.uterus.anchored_depth_mm);
  scene.anchors.push_back(held);
}

}  // namespace hysim::engine::scene_detail

#include "hysim/engine/scene.hpp"

#include "hysim/cutting/input_file.hpp"
#include "hysim/haptics/device.hpp"

#include <yaml-cpp/yaml.h>

#include "hysim/engine/shaving_path.hpp"
#include "scene_reader.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;
using scene_detail::Reader;
using scene_detail::SceneError;

sim::Material parseMaterial(const Reader& r, const YAML::Node& n) {
  r.checkKeys(n, "materials[]", {"name", "label", "young_modulus_kpa", "density_g_cm3", "damping_s"});
  sim::Material m;
  m.name = r.string(r.require(n, "name", "materials[]"), "name");
  m.label = r.integer(r.require(n, "label", "materials[]"), "label", 0, 1 << 30);
  m.young_modulus_pa = 1e3 * r.positive(r.require(n, "young_modulus_kpa", "materials[]"), "young_modulus_kpa");
  m.density_g_mm3 = 1e-3 * r.positive(r.require(n, "density_g_cm3", "materials[]"), "density_g_cm3");
  if (n["damping_s"]) m.stiffness_damping_s = r.nonNegative(n["damping_s"], "damping_s");
  return m;
}

AnchorRegion parseAnchor(const Reader& r, const YAML::Node& n) {
  r.checkKeys(n, "anchors[]", {"box", "sphere", "outside_ellipsoid"});
  if (n.size() != 1) r.fail(n, "each anchor must have exactly one of: box, sphere, outside_ellipsoid");
  AnchorRegion a;
  if (n["box"]) {
    const YAML::Node b = n["box"];
    r.checkKeys(b, "box", {"min", "max"});
    a.kind = AnchorRegion::Kind::Box;
    a.a = r.vec3(r.require(b, "min", "box"), "min");
    a.b = r.vec3(r.require(b, "max", "box"), "max");
    if ((a.b.array() < a.a.array()).any()) r.fail(b, "'box' needs min <= max in every coordinate");
  } else if (n["sphere"]) {
    const YAML::Node s = n["sphere"];
    r.checkKeys(s, "sphere", {"center", "radius"});
    a.kind = AnchorRegion::Kind::Sphere;
    a.a = r.vec3(r.require(s, "center", "sphere"), "center");
    a.b = Eigen::Vector3d(r.positive(r.require(s, "radius", "sphere"), "radius"), 0, 0);
  } else {
    const YAML::Node e = n["outside_ellipsoid"];
    r.checkKeys(e, "outside_ellipsoid", {"center", "radii"});
    a.kind = AnchorRegion::Kind::OutsideEllipsoid;
    a.a = r.vec3(r.require(e, "center", "outside_ellipsoid"), "center");
    a.b = r.vec3(r.require(e, "radii", "outside_ellipsoid"), "radii");
    if ((a.b.array() <= 0.0).any()) r.fail(e, "'radii' must be positive");
  }
  return a;
}

void parseSimulation(const Reader& r, const YAML::Node& n, Scene& scene) {
  r.checkKeys(n, "simulation", {"dt_ms", "steps", "integrator", "substeps", "max_substeps", "implicit_iterations",
                                "xpbd_substeps", "xpbd_iterations", "drag_per_s", "gravity_mm_s2", "max_speed_mm_s"});
  if (n["dt_ms"]) {
    const double dt_ms = r.positive(n["dt_ms"], "dt_ms");
    if (dt_ms > 100.0) r.fail(n["dt_ms"], "'dt_ms' must be at most 100, got " + n["dt_ms"].Scalar());
    scene.sim.dt = 1e-3 * dt_ms;
  }
  if (n["steps"]) scene.steps = r.integer(n["steps"], "steps", 0, 100000000);
  if (n["integrator"]) {
    const std::string s = r.string(n["integrator"], "integrator");
    if (s == "symplectic_euler") scene.sim.integrator = sim::Integrator::SymplecticEuler;
    else if (s == "implicit_euler") scene.sim.integrator = sim::Integrator::ImplicitEuler;
    else if (s == "xpbd") scene.sim.integrator = sim::Integrator::Xpbd;
    else r.fail(n["integrator"], "'integrator' must be symplectic_euler, implicit_euler or xpbd, got '" + s + "'");
  }
  if (n["substeps"]) {
    if (n["substeps"].IsScalar() && n["substeps"].Scalar() == "auto") scene.sim.substeps = 0;
    else scene.sim.substeps = r.integer(n["substeps"], "substeps", 1, 10000);
  }
  if (n["max_substeps"]) scene.sim.max_substeps = r.integer(n["max_substeps"], "max_substeps", 1, 10000);
  if (n["implicit_iterations"]) scene.sim.implicit_iterations = r.integer(n["implicit_iterations"], "implicit_iterations", 1, 1000);
  if (n["xpbd_substeps"]) {
    if (n["xpbd_substeps"].IsScalar() && n["xpbd_substeps"].Scalar() == "auto") scene.sim.xpbd_substeps = 0;
    else scene.sim.xpbd_substeps = r.integer(n["xpbd_substeps"], "xpbd_substeps", 1, 10000);
  }
  if (n["xpbd_iterations"]) scene.sim.xpbd_iterations = r.integer(n["xpbd_iterations"], "xpbd_iterations", 1, 1000);
  if (n["drag_per_s"]) scene.sim.drag_per_s = r.nonNegative(n["drag_per_s"], "drag_per_s");
  if (n["gravity_mm_s2"]) scene.sim.gravity = r.vec3(n["gravity_mm_s2"], "gravity_mm_s2");
  if (n["max_speed_mm_s"]) scene.sim.max_speed_mm_s = r.positive(n["max_speed_mm_s"], "max_speed_mm_s");
}

void parseContact(const Reader& r, const YAML::Node& n, ContactSettings& c) {
  r.checkKeys(n, "contact", {"enabled", "stiffness_n_per_mm", "damping_n_s_per_mm", "shaft_radius_mm",
                             "shaft_length_mm", "loop_radius_mm", "loop_reach_mm", "loop_drop_mm"});
  if (n["enabled"]) c.enabled = r.boolean(n["enabled"], "enabled");
  if (n["stiffness_n_per_mm"]) c.stiffness_n_per_mm = r.nonNegative(n["stiffness_n_per_mm"], "stiffness_n_per_mm");
  if (n["damping_n_s_per_mm"]) c.damping_n_s_per_mm = r.nonNegative(n["damping_n_s_per_mm"], "damping_n_s_per_mm");
  if (n["shaft_radius_mm"]) c.shaft_radius_mm = r.positive(n["shaft_radius_mm"], "shaft_radius_mm");
  if (n["shaft_length_mm"]) c.shaft_length_mm = r.positive(n["shaft_length_mm"], "shaft_length_mm");
  if (n["loop_radius_mm"]) c.loop_radius_mm = r.positive(n["loop_radius_mm"], "loop_radius_mm");
  if (n["loop_reach_mm"]) c.loop_reach_mm = r.number(n["loop_reach_mm"], "loop_reach_mm");
  if (n["loop_drop_mm"]) c.loop_drop_mm = r.number(n["loop_drop_mm"], "loop_drop_mm");
}

// `chips: remove` / `chips: simulate`, or a mapping with `mode` and the tuning keys.
void parseChips(const Reader& r, const YAML::Node& n, ChipSettings& c) {
  auto mode = [&](const YAML::Node& m) {
    const std::string s = r.string(m, "chips");
    if (s == "remove") c.mode = ChipSettings::Mode::Remove;
    else if (s == "simulate") c.mode = ChipSettings::Mode::Simulate;
    else r.fail(m, "'chips' must be remove or simulate, got '" + s + "'");
  };
  if (n.IsScalar()) {
    mode(n);
    return;
  }
  r.checkKeys(n, "chips",
              {"mode", "max_chips", "drag_per_s", "angular_drag_per_s", "fluid_density_g_cm3", "friction", "optimize"});
  if (n["mode"]) mode(n["mode"]);
  if (n["max_chips"]) c.max_chips = r.integer(n["max_chips"], "max_chips", 1, 256);
  if (n["drag_per_s"]) c.drag_per_s = r.nonNegative(n["drag_per_s"], "drag_per_s");
  if (n["angular_drag_per_s"]) c.angular_drag_per_s = r.nonNegative(n["angular_drag_per_s"], "angular_drag_per_s");
  if (n["fluid_density_g_cm3"]) c.fluid_density_g_cm3 = r.nonNegative(n["fluid_density_g_cm3"], "fluid_density_g_cm3");
  if (n["friction"]) c.friction = r.nonNegative(n["friction"], "friction");
  if (n["optimize"]) c.optimize = r.boolean(n["optimize"], "optimize");
}

haptics::Keyframe parseKeyframe(const Reader& r, const YAML::Node& n, const haptics::Keyframe* previous) {
  r.checkKeys(n, "tool_path[]", {"t_s", "tip", "axis", "up", "extension_mm", "pedal", "move", "arc_center"});
  const double previous_time = previous != nullptr ? previous->time_s : 0.0;
  haptics::Keyframe k;
  k.time_s = r.nonNegative(r.require(n, "t_s", "tool_path[]"), "t_s");
  if (k.time_s < previous_time) {
    r.fail(n["t_s"], "'t_s' must not decrease along tool_path (" + n["t_s"].Scalar() + " after " +
                         std::to_string(previous_time) + ")");
  }
  k.tip = r.vec3(r.require(n, "tip", "tool_path[]"), "tip");
  k.axis = r.unitVec3(r.require(n, "axis", "tool_path[]"), "axis");
  if (n["up"]) k.up = r.unitVec3(n["up"], "up");
  if (std::abs(k.up.dot(k.axis)) > 0.999) r.fail(n["up"] ? n["up"] : n, "'up' must not be parallel to 'axis'");
  if (n["extension_mm"]) {
    k.extension_mm = r.number(n["extension_mm"], "extension_mm");
    if (k.extension_mm < 0.0 || k.extension_mm > haptics::kMaxLoopExtensionMm) {
      r.fail(n["extension_mm"], "'extension_mm' must be in [0, 100], got " + n["extension_mm"].Scalar());
    }
  }
  if (n["pedal"]) k.pedal = r.boolean(n["pedal"], "pedal");
  if (n["move"]) {
    const std::string move = r.string(n["move"], "move");
    if (move == "linear") k.move = haptics::Keyframe::Move::Linear;
    else if (move == "arc") k.move = haptics::Keyframe::Move::Arc;
    else r.fail(n["move"], "'move' must be linear or arc, got '" + move + "'");
  }
  if (k.move == haptics::Keyframe::Move::Arc) {
    k.arc_center = r.vec3(r.require(n, "arc_center", "tool_path[]"), "arc_center");
    if (previous == nullptr) r.fail(n["move"], "the first keyframe cannot be an arc move");
    if (!haptics::validArc(previous->tip, k.tip, k.arc_center)) {
      r.fail(n["arc_center"], "arc from the previous tip to 'tip' about 'arc_center' is undefined "
                              "(an end at the centre, or ends 0 or 180 degrees apart)");
    }
  } else if (n["arc_center"]) {
    r.fail(n["arc_center"], "'arc_center' needs 'move: arc'");
  }
  return k;
}

void parseCut(const Reader& r, const YAML::Node& n, CutSettings& c) {
  r.checkKeys(n, "cut", {"mode", "commit_steps"});
  if (n["mode"]) {
    const std::string s = r.string(n["mode"], "mode");
    if (s == "async") c.mode = CutSettings::Mode::Async;
    else if (s == "sync") c.mode = CutSettings::Mode::Sync;
    else r.fail(n["mode"], "'cut.mode' must be async or sync, got '" + s + "'");
  }
  if (n["commit_steps"]) c.commit_steps = r.integer(n["commit_steps"], "commit_steps", 0, 1000);
}

void parseCoupling(const Reader& r, const YAML::Node& n, CouplingSettings& c) {
  r.checkKeys(n, "coupling", {"mode", "stiffness_n_per_mm", "damping_n_s_per_mm"});
  if (n["mode"]) {
    const std::string s = r.string(n["mode"], "mode");
    if (s == "spring") c.mode = CouplingSettings::Mode::Spring;
    else if (s == "rigid") c.mode = CouplingSettings::Mode::Rigid;
    else r.fail(n["mode"], "'coupling.mode' must be spring or rigid, got '" + s + "'");
  }
  if (n["stiffness_n_per_mm"]) c.stiffness_n_per_mm = r.positive(n["stiffness_n_per_mm"], "stiffness_n_per_mm");
  if (n["damping_n_s_per_mm"]) c.damping_n_s_per_mm = r.positive(n["damping_n_s_per_mm"], "damping_n_s_per_mm");
}

// The instructor's thresholds and weights (assessment.hpp); a weight of 0 leaves an item out
// of the score, but all of them 0 would leave no score.
void parseAssessment(const Reader& r, const YAML::Node& n, AssessmentSettings& a) {
  r.checkKeys(n, "assessment", {"min_resected_pct", "max_healthy_removed_mm3", "perforations_allowed", "time_limit_s",
                                "weights"});
  if (n["min_resected_pct"]) {
    a.min_resected_pct = r.nonNegative(n["min_resected_pct"], "min_resected_pct");
    if (a.min_resected_pct > 100.0) {
      r.fail(n["min_resected_pct"], "'min_resected_pct' must be at most 100, got " + n["min_resected_pct"].Scalar());
    }
  }
  if (n["max_healthy_removed_mm3"]) a.max_healthy_removed_mm3 = r.nonNegative(n["max_healthy_removed_mm3"], "max_healthy_removed_mm3");
  if (n["perforations_allowed"]) a.perforations_allowed = r.integer(n["perforations_allowed"], "perforations_allowed", 0, 1000);
  if (n["time_limit_s"]) a.time_limit_s = r.positive(n["time_limit_s"], "time_limit_s");
  if (!n["weights"]) return;
  const YAML::Node w = n["weights"];
  r.checkKeys(w, "assessment.weights", {"resection", "healthy", "safety", "time"});
  if (w["resection"]) a.weights.resection = r.nonNegative(w["resection"], "resection");
  if (w["healthy"]) a.weights.healthy = r.nonNegative(w["healthy"], "healthy");
  if (w["safety"]) a.weights.safety = r.nonNegative(w["safety"], "safety");
  if (w["time"]) a.weights.time = r.nonNegative(w["time"], "time");
  if (!(a.weights.resection + a.weights.healthy + a.weights.safety + a.weights.time > 0.0)) {
    r.fail(w, "'assessment.weights' must not all be 0");
  }
}

// The case as the start screen lists it: FIGO type (0-7, or 2-5 for the hybrid) and difficulty.
void parseCase(const Reader& r, const YAML::Node& root, Scene& scene) {
  if (root["figo_type"]) {
    const std::string t = r.string(root["figo_type"], "figo_type");
    static const std::set<std::string> kTypes = {"0", "1", "2", "3", "4", "5", "6", "7", "2-5"};
    if (!kTypes.count(t)) r.fail(root["figo_type"], "'figo_type' must be 0 to 7 or 2-5, got '" + t + "'");
    scene.figo_type = t;
  }
  if (root["difficulty"]) {
    const std::string d = r.string(root["difficulty"], "difficulty");
    if (d != "beginner" && d != "intermediate" && d != "advanced") {
      r.fail(root["difficulty"], "'difficulty' must be beginner, intermediate or advanced, got '" + d + "'");
    }
    scene.difficulty = d;
  }
}

void parseMaterials(const Reader& r, const YAML::Node& mats, Scene& scene) {
  if (!mats.IsSequence() || mats.size() == 0) r.fail(mats, "'materials' must be a non-empty list");
  std::set<int> labels;
  for (const auto& m : mats) {
    scene.materials.push_back(parseMaterial(r, m));
    if (!labels.insert(scene.materials.back().label).second) {
      r.fail(m, "material label " + std::to_string(scene.materials.back().label) + " is used twice");
    }
  }
}

// Keyframes, or `auto`: a level-by-level resection of the organ's myomas (shaving_path.hpp).
void parseToolPath(const Reader& r, const YAML::Node& tp, Scene& scene) {
  if (tp.IsScalar() && tp.Scalar() == "auto") {
    if (!scene.organ.given) r.fail(tp, "'tool_path: auto' needs an 'organ' section");
    scene.auto_tool_path = true;
    scene.tool_path = planShavingPath(scene.organ, scene.contact, scene.safety.perforation_margin_mm);
    if (scene.tool_path.empty()) r.fail(tp, "'tool_path: auto' found no myoma the loop can reach (FIGO 0 to 4 or 2-5)");
    return;
  }
  if (!tp.IsSequence() || tp.size() == 0) r.fail(tp, "'tool_path' must be a non-empty list of keyframes or 'auto'");
  for (const auto& k : tp) {
    scene.tool_path.push_back(parseKeyframe(r, k, scene.tool_path.empty() ? nullptr : &scene.tool_path.back()));
  }
}

Scene parse(const Reader& r, const YAML::Node& root, const std::string& path) {
  Scene scene;
  scene.path = path;
  if (!root.IsDefined() || root.IsNull()) r.fail(root, "the scene file is empty");
  r.checkKeys(root, "scene", {"name", "description", "mesh", "tool_mesh", "materials", "anchors", "simulation",
                              "contact", "safety", "tool_path", "camera", "render", "chips", "cut",
                              "coupling", "figo_type", "difficulty", "assessment", "organ"});
  const fs::path dir = fs::path(path).parent_path();
  auto resolve = [&](const YAML::Node& n, const std::string& key) {
    const std::string rel = r.string(n, key);
    const fs::path p = fs::path(rel).is_absolute() ? fs::path(rel) : dir / rel;
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) r.fail(n, "'" + key + "' file '" + p.string() + "' does not exist");
    return p.lexically_normal().string();
  };
  scene.name = r.string(r.require(root, "name", "scene"), "name");
  if (root["description"]) scene.description = r.string(root["description"], "description");
  parseCase(r, root, scene);
  if (root["assessment"]) parseAssessment(r, root["assessment"], scene.assessment);
  if (root["organ"]) {
    // A generated organ brings its own materials and its anchored outer layer.
    if (root["mesh"]) r.fail(root["mesh"], "give either 'mesh' or 'organ', not both");
    if (root["materials"]) r.fail(root["materials"], "'materials' come from 'organ' (its young_modulus_kpa keys)");
    scene_detail::parseOrgan(r, root["organ"], scene);
  } else {
    scene.mesh_path = resolve(r.require(root, "mesh", "scene"), "mesh");
    parseMaterials(r, r.require(root, "materials", "scene"), scene);
  }
  if (root["tool_mesh"]) scene.tool_mesh_path = resolve(root["tool_mesh"], "tool_mesh");
  if (root["anchors"]) {
    const YAML::Node an = root["anchors"];
    if (!an.IsSequence()) r.fail(an, "'anchors' must be a list");
    for (const auto& a : an) scene.anchors.push_back(parseAnchor(r, a));
  }
  if (root["simulation"]) parseSimulation(r, root["simulation"], scene);
  if (root["contact"]) parseContact(r, root["contact"], scene.contact);
  if (root["safety"]) {
    const YAML::Node s = root["safety"];
    r.checkKeys(s, "safety", {"perforation_margin_mm"});
    if (s["perforation_margin_mm"]) {
      scene.safety.perforation_margin_mm = r.nonNegative(s["perforation_margin_mm"], "perforation_margin_mm");
      if (scene.safety.perforation_margin_mm > 50.0) {
        r.fail(s["perforation_margin_mm"], "'perforation_margin_mm' must be at most 50, got " + s["perforation_margin_mm"].Scalar());
      }
    }
  }
  if (root["chips"]) parseChips(r, root["chips"], scene.chips);
  if (root["cut"]) parseCut(r, root["cut"], scene.cut);
  if (root["coupling"]) parseCoupling(r, root["coupling"], scene.coupling);

  parseToolPath(r, r.require(root, "tool_path", "scene"), scene);
  if (scene.auto_tool_path && !(root["simulation"] && root["simulation"]["steps"])) {
    scene.steps = static_cast<int>(std::ceil(scene.tool_path.back().time_s / scene.sim.dt));
  }
  if (root["camera"]) {
    const YAML::Node c = root["camera"];
    r.checkKeys(c, "camera", {"lens_deg", "fov_deg", "light"});
    if (c["lens_deg"]) {
      scene.camera.lens_deg = r.number(c["lens_deg"], "lens_deg");
      if (scene.camera.lens_deg < 0.0 || scene.camera.lens_deg > 70.0) r.fail(c["lens_deg"], "'lens_deg' must be between 0 and 70");
    }
    if (c["fov_deg"]) {
      scene.camera.fov_deg = r.number(c["fov_deg"], "fov_deg");
      if (scene.camera.fov_deg < 10.0 || scene.camera.fov_deg > 170.0) r.fail(c["fov_deg"], "'fov_deg' must be between 10 and 170");
    }
    if (c["light"]) scene.camera.light = r.positive(c["light"], "light");
  }
  if (root["render"]) {
    const YAML::Node rn = root["render"];
    r.checkKeys(rn, "render", {"width", "height", "every"});
    if (rn["width"]) scene.render.width = r.integer(rn["width"], "width", 16, 8192);
    if (rn["height"]) scene.render.height = r.integer(rn["height"], "height", 16, 8192);
    if (rn["every"]) scene.render.every = r.integer(rn["every"], "every", 1, 1000000);
  }
  return scene;
}

}  // namespace

bool AnchorRegion::contains(const Eigen::Vector3d& p) const {
  switch (kind) {
    case Kind::Box:
      return (p.array() >= a.array()).all() && (p.array() <= b.array()).all();
    case Kind::Sphere:
      return (p - a).norm() <= b.x();
    case Kind::OutsideEllipsoid:
      return ((p - a).array() / b.array()).matrix().squaredNorm() >= 1.0;
  }
  return false;
}

Result<Scene> loadScene(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxYamlFileBytes, "scene");
  if (!text.ok()) return Error{text.error()};
  return parseScene(*text, path);
}

Result<Scene> parseScene(const std::string& text, const std::string& path) {
  const Reader reader(path);
  try {
    const YAML::Node root = YAML::Load(text);
    long visited = 0;
    reader.checkDocument(root, "scene", 0, visited);
    return parse(reader, root, path);
  } catch (const SceneError& e) {
    return Error{e.message};
  } catch (const YAML::Exception& e) {
    // yaml-cpp marks are 0-based.
    return Error{path + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                 ": YAML error: " + e.msg};
  }
}

}  // namespace hysim::engine

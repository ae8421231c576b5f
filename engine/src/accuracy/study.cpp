#include "hysim/engine/accuracy/study.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "cut_methods.hpp"
#include "fields.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/accuracy/calculix.hpp"
#include "hysim/engine/accuracy/runs.hpp"
#include "report_writer.hpp"

namespace hysim::engine::accuracy {
namespace {

using nlohmann::json;

struct Context {
  const StudyOptions& options;
  double done = 0.0, total = 1.0;
  void progress(const std::string& what, double weight = 1.0) {
    done += weight;
    if (options.progress) options.progress(std::min(1.0, done / total), what);
  }
  std::string ccxDir() const { return (std::filesystem::path(options.out_dir) / "calculix").string(); }
};

// Every setting the study runs on a dynamic case. `auto_substeps`: symplectic Euler's
// automatic substeps on the case (its multiples are the 0.5x / 2x settings).
std::vector<Setting> dynamicSettings(int auto_substeps, bool quick) {
  std::vector<Setting> out;
  auto add = [&out](std::string family, std::string label, sim::ModelOptions o) {
    out.push_back(Setting{std::move(family), std::move(label), o, false, {}});
  };
  sim::ModelOptions base;
  base.max_substeps = 0;
  for (double factor : {0.5, 1.0, 2.0}) {
    sim::ModelOptions o = base;
    o.substeps = std::max(1, static_cast<int>(std::lround(factor * auto_substeps)));
    add("symplectic_euler", "symplectic " + std::to_string(o.substeps) + " substeps" + (factor == 1.0 ? " (auto)" : ""), o);
  }
  const std::vector<int> iterations = quick ? std::vector<int>{1, 4} : std::vector<int>{1, 2, 4, 8, 16};
  for (int it : iterations) {
    sim::ModelOptions o = base;
    o.integrator = sim::Integrator::ImplicitEuler;
    o.implicit_iterations = it;
    add("implicit_euler", "implicit dt 1 ms, " + std::to_string(it) + " it", o);
  }
  const std::vector<double> dts = quick ? std::vector<double>{16} : std::vector<double>{2, 5, 16};
  for (double dt_ms : dts) {
    sim::ModelOptions o = base;
    o.integrator = sim::Integrator::ImplicitEuler;
    o.dt = dt_ms * 1e-3;
    add("implicit_euler", "implicit dt " + std::to_string(static_cast<int>(dt_ms)) + " ms, 8 it", o);
  }
  // XPBD: the automatic substeps are symplectic Euler's; it is stable with fewer.
  for (double factor : quick ? std::vector<double>{1, 2} : std::vector<double>{0.25, 0.5, 1, 2, 4}) {
    sim::ModelOptions o = base;
    o.integrator = sim::Integrator::Xpbd;
    o.xpbd_substeps = std::max(1, static_cast<int>(std::lround(factor * auto_substeps)));
    add("xpbd", "xpbd " + std::to_string(o.xpbd_substeps) + " substeps", o);
  }
  for (int pit : quick ? std::vector<int>{4} : std::vector<int>{1, 4, 16}) {
    Setting s{"bullet", "bullet btSoftBody " + std::to_string(pit) + " it", base, true, {}};
    s.bullet_options.position_iterations = pit;
    out.push_back(s);
  }
  return out;
}

// R1 in time: symplectic Euler at an eighth of its automatic substep (halving it again moves
// the trajectory by the `self_check` the report prints).
Setting referenceSetting(int auto_substeps, int factor) {
  sim::ModelOptions o;
  o.max_substeps = 0;
  o.substeps = factor * auto_substeps;
  return Setting{"reference", "R1: symplectic " + std::to_string(o.substeps) + " substeps", o, false, {}};
}

int autoSubsteps(const AccuracyCase& c) {
  sim::ModelOptions o;
  o.max_substeps = 0;
  auto m = caseModel(c, o);
  return m.ok() ? m->substeps : 1;
}

json runJson(const Setting& s, const Trajectory& t, double error) {
  const Cost cost = costOf(t);
  const Oscillation osc = oscillationOf(t.probe, t.dt);
  json j;
  j["label"] = s.label;
  j["family"] = s.family;
  j["dt_ms"] = t.dt * 1e3;
  j["substeps"] = s.family == "symplectic_euler" || s.family == "xpbd" ? t.substeps : 0;
  j["iterations"] = s.family == "implicit_euler" ? s.options.implicit_iterations
                    : s.family == "xpbd"          ? s.options.xpbd_iterations
                    : s.bullet                   ? s.bullet_options.position_iterations
                                                 : 0;
  j["diverged"] = t.diverged;
  j["error_vs_r1"] = std::isfinite(error) ? json(error) : json(nullptr);
  j["median_ms_per_s"] = t.diverged ? json(nullptr) : json(cost.median_ms_per_s);
  j["p99_ms_per_s"] = t.diverged ? json(nullptr) : json(cost.p99_ms_per_s);
  j["frequency_hz"] = osc.frequency_hz;
  j["amplitude_ratio"] = osc.amplitude_ratio;
  // Relative to the largest spring energy reached: the total can be near zero.
  j["energy_change"] = (t.max_spring_energy > 0.0 && !s.bullet && !t.diverged)
                           ? json((t.energy_end - t.energy_start) / t.max_spring_energy)
                           : json(nullptr);
  return j;
}

// The cheapest-first non-dominated set (lower cost and lower error) among finite points.
void markPareto(json& runs) {
  for (auto& r : runs) {
    bool dominated = r["error_vs_r1"].is_null();
    for (const auto& o : runs) {
      if (dominated || &o == &r || o["error_vs_r1"].is_null()) continue;
      const double ce = o["median_ms_per_s"], ee = o["error_vs_r1"], cr = r["median_ms_per_s"], er = r["error_vs_r1"];
      if (ce <= cr && ee <= er && (ce < cr || ee < er)) dominated = true;
    }
    r["pareto"] = !dominated;
  }
}

json dynamicSweep(Context& ctx, const AccuracyCase& c, const RunSpec& spec, const Eigen::MatrixX3d* r1_static = nullptr) {
  const int auto_sub = autoSubsteps(c);
  const Trajectory ref = runTrajectory(c, referenceSetting(auto_sub, 8), spec);
  json out;
  out["reference"] = referenceSetting(auto_sub, 8).label;
  if (!ctx.options.quick) {
    const Trajectory ref2 = runTrajectory(c, referenceSetting(auto_sub, 16), spec);
    out["reference_self_check"] = trajectoryError(ref, ref2, c.mesh.X);
  }
  out["reference_frequency_hz"] = oscillationOf(ref.probe, ref.dt).frequency_hz;
  out["duration_s"] = spec.duration_s;
  out["nodes"] = c.mesh.numNodes();
  out["tets"] = c.mesh.numTets();
  json runs = json::array();
  const std::vector<Setting> settings = dynamicSettings(auto_sub, ctx.options.quick);
  for (const Setting& s : settings) {
    const Trajectory t = runTrajectory(c, s, spec);
    json j = runJson(s, t, trajectoryError(t, ref, c.mesh.X));
    if (r1_static != nullptr && !t.diverged && !t.samples.empty())
      j["final_error_vs_r1_static"] = relativeFieldError(t.samples.back() - c.mesh.X, *r1_static);
    runs.push_back(j);
    ctx.progress(c.name + ": " + s.label);
  }
  markPareto(runs);
  out["runs"] = runs;
  return out;
}

json feJson(const std::string& name, const Result<FeSolution>& fe, const Eigen::MatrixX3d& u_r1, int probe) {
  json j;
  j["name"] = name;
  if (!fe.ok()) {
    j["error"] = fe.error();
    return j;
  }
  j["ccx_seconds"] = fe->seconds;
  j["probe_displacement_mm"] = fe->u.row(probe).norm();
  j["max_displacement_mm"] = fe->u.rowwise().norm().maxCoeff();
  j["spring_error_vs_this"] = relativeFieldError(u_r1, fe->u);
  const Calibration cal = calibrate(u_r1, fe->u);
  j["calibration_stiffness_scale"] = cal.stiffness_scale;
  j["spring_error_after_calibration"] = cal.error_after;
  return j;
}

// The FE references of one static case: C3D4 on the same mesh (to show its locking), C3D10
// linear and nonlinear on the same mesh, C3D10 linear on `fine` (interpolated at our nodes).
json feReferences(Context& ctx, const AccuracyCase& c, const Eigen::MatrixX3d& u_r1, int probe, const AccuracyCase* fine) {
  json fe = json::array();
  FeOptions o;
  o.program = ctx.options.calculix;
  o.quadratic = false;
  if (!ctx.options.quick || c.mesh.numTets() < 5000)
    fe.push_back(feJson("R2 CalculiX C3D4 linear, same mesh", solveCalculix(c, o, ctx.ccxDir(), c.name + "_c3d4"), u_r1, probe));
  o.quadratic = true;
  fe.push_back(feJson("R2 CalculiX C3D10 linear, same mesh", solveCalculix(c, o, ctx.ccxDir(), c.name + "_c3d10"), u_r1, probe));
  if (ctx.options.quick) return fe;
  FeOptions nl = o;
  nl.nlgeom = true;
  nl.increments = 2;
  fe.push_back(feJson("R2 CalculiX C3D10 nonlinear, same mesh", solveCalculix(c, nl, ctx.ccxDir(), c.name + "_c3d10_nlgeom"), u_r1, probe));
  if (fine != nullptr) {
    auto fe_fine = solveCalculix(*fine, o, ctx.ccxDir(), c.name + "_c3d10_refined");
    if (fe_fine.ok()) fe_fine->u = interpolateAtNodes(fine->mesh, fe_fine->u, c.mesh);
    fe.push_back(feJson("R2 CalculiX C3D10 linear, refined mesh (" + std::to_string(fine->mesh.numTets()) + " tets)", fe_fine,
                        u_r1, probe));
  }
  return fe;
}

int nearestNode(const cutting::TetMesh& m, const Eigen::Vector3d& p) {
  Eigen::Index i = 0;
  (m.X.rowwise() - p.transpose()).rowwise().squaredNorm().minCoeff(&i);
  return static_cast<int>(i);
}

json beamSection(Context& ctx) {
  BeamSpec spec;
  if (ctx.options.quick) spec.cell_mm = 5.0;
  const AccuracyCase beam = beamCase(spec);
  const int tip = nearestNode(beam.mesh, beam.probe);
  json out;
  out["spec"] = {{"length_mm", spec.length_mm}, {"width_mm", spec.width_mm}, {"cell_mm", spec.cell_mm},
                 {"young_kpa", spec.young_pa * 1e-3}, {"density_g_cm3", spec.density_g_mm3 * 1e3}};
  out["r3"] = {{"tip_sag_mm", beamTipSagMm(spec)}, {"first_frequency_hz", beamFirstFrequencyHz(spec)}};
  auto u_r1 = springStatic(beam);
  if (!u_r1.ok()) return {{"error", u_r1.error()}};
  out["r1"] = {{"tip_sag_mm", -u_r1->row(tip).z()}};
  BeamSpec fine_spec = spec;
  fine_spec.cell_mm = spec.cell_mm / 2;
  const AccuracyCase fine_beam = beamCase(fine_spec);
  json fe = feReferences(ctx, beam, *u_r1, tip, &fine_beam);
  FeOptions lin;
  lin.program = ctx.options.calculix;
  FeOptions freq = lin;
  freq.frequencies = 1;
  auto f = solveCalculix(beam, freq, ctx.ccxDir(), "beam_frequency");
  out["r2_first_frequency_hz"] = f.ok() && !f->frequencies_hz.empty() ? json(f->frequencies_hz[0]) : json(nullptr);
  for (auto& j : fe) j["tip_sag_mm"] = j.contains("probe_displacement_mm") ? j["probe_displacement_mm"] : json(nullptr);
  out["r2"] = fe;
  ctx.progress("beam: references");
  AccuracyCase dyn = beam;  // released from rest under gravity, undamped: oscillates about the sag
  RunSpec rs;
  rs.duration_s = ctx.options.quick ? 0.16 : 0.4;
  out["dynamic"] = dynamicSweep(ctx, dyn, rs, &u_r1.value());
  return out;
}

// The indenter's force (mN) at each depth from ccx's increments: a linear analysis solves once
// (its force scales with the depth); a nonlinear one is interpolated between its increments,
// null beyond the last one it reached.
json forcesAtDepths(const FeSolution& fe, const std::vector<double>& depths, const Eigen::Vector3d& dir, bool nonlinear) {
  json f = json::array();
  std::vector<double> t = {0.0}, force = {0.0};
  for (size_t k = 0; k < fe.indenter_forces.size() && k < fe.increment_times.size(); ++k) {
    t.push_back(fe.increment_times[k]);
    force.push_back(fe.indenter_forces[k].dot(dir) * 1e-3);
  }
  for (double d : depths) {
    const double at = d / depths.back();
    if (!nonlinear && t.size() > 1) {
      f.push_back(force.back() * at / t.back());
      continue;
    }
    size_t k = 1;
    while (k < t.size() && t[k] < at - 1e-9) ++k;
    if (k >= t.size()) {
      f.push_back(nullptr);
      continue;
    }
    const double w = (at - t[k - 1]) / (t[k] - t[k - 1]);
    f.push_back(force[k - 1] + w * (force[k] - force[k - 1]));
  }
  return f;
}

json indentationSection(Context& ctx, const AccuracyCase& organ) {
  const std::vector<double> depths = {1, 2, 3, 4, 5};
  json out;
  out["depth_mm"] = depths;
  out["indenter_nodes"] = organ.indenter.size();
  json r1 = json::array();
  if (auto f = springIndentation(organ, depths, false); f.ok())
    for (double v : *f) r1.push_back(v * 1e-3);  // uN -> mN
  else
    out["r1_error"] = f.error();
  out["r1_force_mn"] = r1;
  AccuracyCase no_gravity = organ;
  no_gravity.gravity.setZero();
  for (bool nlgeom : {false, true}) {
    if (ctx.options.quick) continue;
    FeOptions o;
    o.program = ctx.options.calculix;
    o.gravity = false;
    o.nlgeom = nlgeom;
    o.hold_indenter = true;
    o.indent_mm = depths.back();
    o.increments = static_cast<int>(depths.size());
    auto fe = solveCalculix(no_gravity, o, ctx.ccxDir(), nlgeom ? "indent_nlgeom" : "indent_linear");
    json f = fe.ok() ? forcesAtDepths(*fe, depths, organ.indent_direction, nlgeom) : json(nullptr);
    out[nlgeom ? "r2_nonlinear_force_mn" : "r2_linear_force_mn"] = fe.ok() ? f : json(fe.error());
  }
  ctx.progress("organ: indentation");
  return out;
}

// The per-material fit against the C3D10 linear reference on the same mesh.
json perMaterialCalibration(Context& ctx, const AccuracyCase& organ, const Eigen::MatrixX3d& u_r1) {
  FeOptions o;
  o.program = ctx.options.calculix;
  auto fe = solveCalculix(organ, o, ctx.ccxDir(), "organ_calibration");
  if (!fe.ok()) return {{"error", fe.error()}};
  const Calibration one = calibrate(u_r1, fe->u);
  auto cal = calibratePerMaterial(organ, fe->u, one.stiffness_scale);
  if (!cal.ok()) return {{"error", cal.error()}};
  json j;
  j["against"] = "R2 CalculiX C3D10 linear, same mesh";
  j["error_before"] = relativeFieldError(u_r1, fe->u);
  j["error_after_one_scale"] = one.error_after;
  j["error_after"] = cal->error_after;
  j["static_solves"] = cal->solves;
  json scales = json::array();
  for (size_t m = 0; m < cal->labels.size(); ++m)
    scales.push_back({{"material", organ.materials[m].name}, {"label", cal->labels[m]}, {"stiffness_scale", cal->stiffness_scales[m]}});
  j["scales"] = scales;
  return j;
}

json organStaticSection(Context& ctx, const AccuracyCase& organ, const Scene& scene) {
  const int probe = nearestNode(organ.mesh, organ.probe);
  auto u_r1 = springStatic(organ);
  if (!u_r1.ok()) return {{"error", u_r1.error()}};
  json out;
  out["r1"] = {{"max_sag_mm", u_r1->rowwise().norm().maxCoeff()}, {"probe_displacement_mm", u_r1->row(probe).norm()}};
  AccuracyCase fine = organ;
  bool have_fine = false;
  if (!ctx.options.quick && !ctx.options.refined_mesh.empty()) {
    auto mesh = cutting::readTetMesh(ctx.options.refined_mesh);
    if (mesh.ok()) {
      fine.mesh = std::move(mesh.value());
      fine.fixed = anchoredNodes(scene, fine.mesh);
      have_fine = true;
    } else {
      out["refined_mesh_error"] = mesh.error();
    }
  }
  json fe = feReferences(ctx, organ, *u_r1, probe, have_fine ? &fine : nullptr);
  if (!ctx.options.quick) out["per_material_calibration"] = perMaterialCalibration(ctx, organ, *u_r1);
  out["r2"] = fe;
  ctx.progress("organ: static references");
  return out;
}

json organSection(Context& ctx) {
  auto scene = loadScene(ctx.options.scene_path);
  if (!scene.ok()) return {{"error", scene.error()}};
  auto organ = organCase(*scene, "", 4.0);
  if (!organ.ok()) return {{"error", organ.error()}};
  json out;
  out["mesh"] = scene->mesh_path;
  out["static"] = organStaticSection(ctx, *organ, *scene);
  out["indentation"] = indentationSection(ctx, *organ);
  RunSpec rs;
  rs.duration_s = ctx.options.quick ? 0.08 : 0.4;
  rs.sample_every_s = ctx.options.quick ? 0.016 : 0.08;
  auto u_sag = springStatic(*organ);
  out["sag"] = dynamicSweep(ctx, *organ, rs, u_sag.ok() ? &u_sag.value() : nullptr);
  // Release: from the spring network's 5 mm indentation at rest, the indenter lets go.
  Eigen::MatrixX3d u;
  if (springIndentation(*organ, {1, 2, 3, 4, 5}, true, &u).ok()) {
    const sim::NodeVectors start = organ->mesh.X + u;
    rs.start = &start;
    AccuracyCase release = *organ;
    release.name = "organ release";
    out["release"] = dynamicSweep(ctx, release, rs, u_sag.ok() ? &u_sag.value() : nullptr);
  }
  out["cutting"] = cutMethodStudy(*organ, *scene, ctx.options.quick ? std::vector<int>{1} : std::vector<int>{1, 5, 20});
  ctx.progress("organ: cutting methods", 3.0);
  return out;
}

// The cheapest setting whose error against R1 is within 5% on the organ's sag: what the model
// can reach against R2 is then the converged network's error, give or take 5%.
json chooseForScene(const json& organ) {
  json best;
  if (!organ.contains("sag")) return best;
  for (const auto& r : organ["sag"]["runs"]) {
    if (r["error_vs_r1"].is_null() || r["family"] == "bullet" || double(r["error_vs_r1"]) > 0.05) continue;
    if (best.is_null() || double(r["median_ms_per_s"]) < double(best["median_ms_per_s"])) best = r;
  }
  return best;
}

}  // namespace

Status runAccuracyStudy(const StudyOptions& options) {
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) return Error{options.out_dir + ": cannot create the output folder (" + ec.message() + ")"};
  if (!calculixAvailable(options.calculix))
    return Error{"accuracy: the CalculiX program '" + options.calculix + "' was not found (tools/install-deps installs calculix-ccx)"};
  Context ctx{options};
  ctx.total = 3.0 * static_cast<double>(dynamicSettings(1, options.quick).size()) + 6.0;
  json report;
  report["quick"] = options.quick;
  report["machine"] = machineDescription();
  report["units"] = "errors are relative (RMS of the difference over RMS of the reference's displacement); cost in ms of wall time per simulated second";
  report["beam"] = beamSection(ctx);
  report["organ"] = organSection(ctx);
  report["choice_for_default_scene"] = chooseForScene(report["organ"]);
  return writeStudyReport(report, options.out_dir, options.gnuplot);
}

}  // namespace hysim::engine::accuracy

#include "report_writer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace hysim::engine::accuracy {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// Through a temporary file and a rename; on any failure the temporary file is removed.
Status writeAtomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  std::error_code ec;
  if (fs::is_directory(path, ec)) return Error{path.string() + ": is a folder, cannot write the file there"};
  bool written = false;
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    written = static_cast<bool>(out.flush());
  }
  if (written) fs::rename(tmp, path, ec);
  if (!written || ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return Error{path.string() + (written ? ": cannot rename the temporary file (" + ec.message() + ")" : ": cannot write")};
  }
  return {};
}

// j[key], or null when j is not an object or has no such key (a section that failed).
json at(const json& j, const char* key) { return j.is_object() && j.contains(key) ? j[key] : json(); }

std::string num(const json& v, const char* fmt = "%.3g") {
  if (!v.is_number()) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v.get<double>());
  return buf;
}

const char* kFamilies[] = {"symplectic_euler", "implicit_euler", "xpbd", "bullet"};

void dynamicTable(std::ostringstream& md, const std::string& title, const json& sweep) {
  if (!sweep.contains("runs")) return;
  md << "\n### " << title << "\n\n" << sweep["nodes"] << " nodes, " << sweep["tets"] << " tets, " << num(at(sweep, "duration_s"))
     << " s simulated. Reference " << sweep["reference"].get<std::string>() << " (halving its substep again moves it by "
     << num(at(sweep, "reference_self_check")) << "); its probe oscillates at " << num(at(sweep, "reference_frequency_hz")) << " Hz.\n\n"
     << "| setting | dt ms | substeps | iterations | error vs R1 | at the end vs R1 static | median ms/s | p99 ms/s | probe Hz | amplitude ratio | energy change | Pareto |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const json& r : sweep["runs"]) {
    md << "| " << r["label"].get<std::string>() << " | " << num(at(r, "dt_ms")) << " | " << r["substeps"] << " | " << r["iterations"]
       << " | " << (r["diverged"].get<bool>() ? std::string("diverged") : num(at(r, "error_vs_r1"))) << " | "
       << (r.contains("final_error_vs_r1_static") ? num(at(r, "final_error_vs_r1_static")) : std::string("-")) << " | "
       << num(at(r, "median_ms_per_s"), "%.1f") << " | " << num(at(r, "p99_ms_per_s"), "%.1f") << " | " << num(at(r, "frequency_hz"))
       << " | " << num(at(r, "amplitude_ratio")) << " | " << num(at(r, "energy_change")) << " | " << (r.value("pareto", false) ? "yes" : "")
       << " |\n";
  }
}

void feTable(std::ostringstream& md, const json& r2, const char* what) {
  md << "\n| reference | " << what << " | max displacement mm | spring network's error against it | stiffness scale fitted | error after the fit | ccx s |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const json& f : r2) {
    if (f.contains("error")) {
      md << "| " << f["name"].get<std::string>() << " | failed: " << f["error"].get<std::string>() << " | | | | | |\n";
      continue;
    }
    md << "| " << f["name"].get<std::string>() << " | " << num(at(f, "probe_displacement_mm")) << " | "
       << num(at(f, "max_displacement_mm")) << " | " << num(at(f, "spring_error_vs_this")) << " | " << num(at(f, "calibration_stiffness_scale")) << " | "
       << num(at(f, "spring_error_after_calibration")) << " | " << num(at(f, "ccx_seconds"), "%.1f") << " |\n";
  }
}

void calibrationLine(std::ostringstream& md, const json& c) {
  if (c.contains("error")) {
    md << "\nPer-material calibration failed: " << c["error"].get<std::string>() << "\n";
    return;
  }
  md << "\nPer-material calibration against " << c["against"].get<std::string>() << ": error " << num(at(c, "error_before"))
     << " before, " << num(at(c, "error_after_one_scale")) << " with one stiffness scale, " << num(at(c, "error_after")) << " with";
  for (const json& s : c["scales"]) md << " " << s["material"].get<std::string>() << " x" << num(at(s, "stiffness_scale"));
  md << " (" << c["static_solves"] << " static solves).\n";
}

void indentationTable(std::ostringstream& md, const json& ind) {
  md << "\n### Organ: indentation of the anterior wall (" << ind["indenter_nodes"]
     << " cavity-surface nodes held and pushed into the wall; no gravity)\n\n| depth mm | R1 springs mN | R2 linear mN | R2 nonlinear mN |\n|---|---|---|---|\n";
  for (size_t k = 0; k < ind["depth_mm"].size(); ++k) {
    auto cell = [&](const char* key) {
      return ind.contains(key) && ind[key].is_array() && k < ind[key].size() ? num(ind[key][k]) : std::string("-");
    };
    md << "| " << num(at(ind, "depth_mm")[k]) << " | " << cell("r1_force_mn") << " | " << cell("r2_linear_force_mn") << " | "
       << cell("r2_nonlinear_force_mn") << " |\n";
  }
}

void cuttingTable(std::ostringstream& md, const json& cut) {
  md << "\n### Organ: cutting methods (20 slices 3 mm apart across the organ, tilted a few degrees from each other, cut in a fixed order; pieces no anchor holds removed)\n\n"
     << "Uncut: " << cut["initial"]["elements"] << " tets, critical explicit step " << num(at(at(cut, "initial"), "critical_dt_ms"))
     << " ms.\n\n| cuts | method | tets | q*_min | min edge mm | critical step ms | vs uncut | substeps at 1 ms | cut ms (all cuts) | volume error | sag error vs exact body |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const json& r : cut["rows"]) {
    md << "| " << r["cuts"] << " | " << r["method"].get<std::string>() << " | ";
    if (r.contains("error")) {
      md << "failed: " << r["error"].get<std::string>() << " | | | | | | | | |\n";
      continue;
    }
    md << r["elements"] << " | " << num(at(r, "q_min")) << " | " << num(at(r, "edge_min_mm")) << " | " << num(at(r, "critical_dt_ms"))
       << " | " << num(at(r, "critical_dt_ratio")) << " | " << num(at(r, "substeps_at_1ms"), "%.0f") << " | " << num(at(r, "cut_ms_total"), "%.0f")
       << " | " << num(at(r, "volume_error")) << " | " << (r.contains("sag_error_vs_exact_body") ? num(at(r, "sag_error_vs_exact_body")) : "-")
       << " |\n";
  }
}

std::string markdown(const json& r, const std::vector<std::string>& plots) {
  std::ostringstream md;
  md << "# Speed against error\n\nMachine: " << r["machine"].get<std::string>() << (r["quick"].get<bool>() ? " (quick run)" : "")
     << ".\n\n" << r["units"].get<std::string>() << ". R1: the same spring network converged (Newton static solve; "
     << "symplectic Euler at a small substep in time). R2: CalculiX, linear tets, Poisson's ratio 0.45. R3: Euler-Bernoulli.\n";
  const json& beam = r["beam"];
  if (beam.contains("r3") && beam.contains("r2")) {
    md << "\n## Beam (cantilever under its own weight)\n\nTip sag: R3 " << num(at(at(beam, "r3"), "tip_sag_mm")) << " mm, R1 (springs) "
       << num(at(at(beam, "r1"), "tip_sag_mm")) << " mm. First frequency: R3 " << num(at(at(beam, "r3"), "first_frequency_hz")) << " Hz, R2 "
       << num(at(beam, "r2_first_frequency_hz")) << " Hz, springs " << num(at(at(beam, "dynamic"), "reference_frequency_hz")) << " Hz.\n";
    feTable(md, beam["r2"], "tip sag mm");
    dynamicTable(md, "Beam: released from rest under gravity (undamped)", beam["dynamic"]);
  }
  const json& organ = r["organ"];
  if (organ.contains("static") && organ["static"].contains("r2")) {
    md << "\n## Organ (" << organ["mesh"].get<std::string>() << ")\n\nSag under gravity, static: R1 max "
       << num(at(at(at(organ, "static"), "r1"), "max_sag_mm")) << " mm.\n";
    feTable(md, organ["static"]["r2"], "anterior wall mm");
    if (organ["static"].contains("per_material_calibration")) calibrationLine(md, organ["static"]["per_material_calibration"]);
    indentationTable(md, organ["indentation"]);
    dynamicTable(md, "Organ: sagging from rest under gravity (the scene's drag)", organ["sag"]);
    if (organ.contains("release")) dynamicTable(md, "Organ: released from a 5 mm indentation", organ["release"]);
    if (organ.contains("cutting")) cuttingTable(md, organ["cutting"]);
  }
  md << "\nBullet's btSoftBody gets the same nodes, masses, anchors and one link per tet edge, but its link "
        "stiffness (m_kLST = 1) is the fraction of each link's error removed per solver iteration, not a spring "
        "constant: how stiff it is depends on the iterations and the step, not on the tissue's E, so no setting of it "
        "is the same material as ours.\n";
  const json& c = r["choice_for_default_scene"];
  md << "\n## For the default scene\n\n"
     << (c.is_null() ? std::string("No setting came within 5% of R1 on the organ's sag.")
                     : "The cheapest setting within 5% of R1 on the organ's sag (so within 5% of what the spring network "
                       "can reach against R2): **" + c["label"].get<std::string>() + "**, " + num(at(c, "median_ms_per_s"), "%.1f") +
                           " ms per simulated second, error " + num(at(c, "error_vs_r1")) + ".")
     << "\n";
  if (!plots.empty()) md << "\n## Plots\n\n";
  for (const std::string& p : plots) md << "![" << p << "](" << p << ")\n";
  return md.str();
}

// A gnuplot script plotting error against cost, one point style per family, the Pareto
// front as a line; the data inline.
std::string paretoScript(const json& sweep, const std::string& title, const std::string& png) {
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,600 noenhanced\nset output '" << png << "'\nset logscale xy\nset grid\n"
     << "set arrow from 1000, graph 0 to 1000, graph 1 nohead dt 2 lc rgb 'gray'\n"
     << "set label 'real time' at 1000, graph 0.95 offset 0.5, 0 tc rgb 'gray'\n"
     << "set title '" << title << "'\nset xlabel 'ms of wall time per simulated second (median)'\n"
     << "set ylabel 'error against R1 (relative)'\nset key outside right\n";
  std::vector<std::pair<double, double>> front;
  std::ostringstream data;
  std::string plot = "plot ";
  for (int f = 0; f < 4; ++f) {
    data << "$F" << f << " << EOD\n";
    for (const json& r : sweep["runs"]) {
      if (r["family"] != kFamilies[f] || r["error_vs_r1"].is_null()) continue;
      const double cost = r["median_ms_per_s"], err = std::max(1e-9, r["error_vs_r1"].get<double>());
      data << cost << " " << err << " \"" << r["label"].get<std::string>() << "\"\n";
      if (r.value("pareto", false)) front.emplace_back(cost, err);
    }
    data << "EOD\n";
    plot += "$F" + std::to_string(f) + " using 1:2 with points pt " + std::to_string(f + 5) + " ps 1.5 title '" + kFamilies[f] + "', ";
  }
  std::sort(front.begin(), front.end());
  data << "$FRONT << EOD\n";
  for (const auto& [cost, err] : front) data << cost << " " << err << "\n";
  data << "EOD\n";
  gp << data.str() << plot << "$FRONT using 1:2 with lines lw 2 lc rgb 'black' title 'Pareto front'\n";
  return gp.str();
}

std::string indentationScript(const json& ind, const std::string& png) {
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,600 noenhanced\nset output '" << png << "'\nset grid\nset title 'Organ: indentation force'\n"
     << "set xlabel 'depth (mm)'\nset ylabel 'force (mN)'\nset key left top\n";
  const char* keys[] = {"r1_force_mn", "r2_linear_force_mn", "r2_nonlinear_force_mn"};
  const char* names[] = {"R1 springs", "R2 CalculiX linear", "R2 CalculiX nonlinear"};
  std::string plot = "plot ";
  for (int k = 0; k < 3; ++k) {
    if (!ind.contains(keys[k]) || !ind[keys[k]].is_array() || ind[keys[k]].empty()) continue;
    gp << "$D" << k << " << EOD\n0 0\n";
    for (size_t i = 0; i < ind[keys[k]].size() && i < ind["depth_mm"].size(); ++i)
      if (ind[keys[k]][i].is_number()) gp << ind["depth_mm"][i].get<double>() << " " << ind[keys[k]][i].get<double>() << "\n";
    gp << "EOD\n";
    plot += "$D" + std::to_string(k) + " using 1:2 with linespoints lw 2 title '" + names[k] + "', ";
  }
  if (plot == "plot ") return "";
  plot.resize(plot.size() - 2);
  return gp.str() + plot + "\n";
}

// Runs gnuplot on each script; returns the PNGs made.
std::vector<std::string> makePlots(const json& r, const fs::path& dir, const std::string& gnuplot) {
  std::vector<std::pair<std::string, std::string>> scripts;  // png, script
  if (r["beam"].contains("dynamic")) scripts.emplace_back("pareto_beam.png", paretoScript(r["beam"]["dynamic"], "Beam released under gravity", "pareto_beam.png"));
  const json& o = r["organ"];
  if (o.contains("sag")) scripts.emplace_back("pareto_organ_sag.png", paretoScript(o["sag"], "Organ sagging under gravity", "pareto_organ_sag.png"));
  if (o.contains("release")) scripts.emplace_back("pareto_organ_release.png", paretoScript(o["release"], "Organ released from a 5 mm indentation", "pareto_organ_release.png"));
  if (o.contains("indentation")) scripts.emplace_back("indentation.png", indentationScript(o["indentation"], "indentation.png"));
  std::vector<std::string> made;
  for (const auto& [png, script] : scripts) {
    if (script.empty()) continue;
    const fs::path gp = dir / (png.substr(0, png.size() - 4) + ".gp");
    if (!writeAtomically(gp, script).ok()) continue;
    const std::string cmd = "cd '" + dir.string() + "' && " + gnuplot + " '" + gp.filename().string() + "' > /dev/null 2>&1";
    if (std::system(cmd.c_str()) == 0 && fs::exists(dir / png)) made.push_back(png);
  }
  return made;
}

}  // namespace

std::string machineDescription() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " logical cores";
}

Status writeStudyReport(const json& report, const std::string& dir, const std::string& gnuplot) {
  const fs::path d(dir);
  // Scene and mesh paths may hold bytes that are not UTF-8: replaced, not fatal.
  const std::string text = report.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
  if (Status s = writeAtomically(d / "report.json", text); !s.ok()) return s;
  const std::vector<std::string> plots = makePlots(report, d, gnuplot);
  return writeAtomically(d / "report.md", markdown(report, plots));
}

}  // namespace hysim::engine::accuracy

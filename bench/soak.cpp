// soak: the default organ's shaving course again and again for a set wall time (a fresh
// simulation per course, as a trainee's reset makes), with a frame rendered every simulated
// second, to show that nothing grows or slows over a long session: resident memory after each
// course, the step's median and 99th percentile, warnings. Not a test (docs/reliability.md).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/render/renderer.hpp"

namespace {

using namespace hysim;

// Resident set size of this process, kB (VmRSS in /proc/self/status); 0 when unreadable.
long residentKb() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      long kb = 0;
      status >> kb;
      return kb;
    }
    status.ignore(1 << 12, '\n');
  }
  return 0;
}

struct Course {
  double wall_s = 0.0;
  double step_median_us = 0.0, step_p99_us = 0.0;
  int warnings = 0, perforations = 0, frames = 0;
  long rss_kb = 0;  // after the course, its simulation gone
  std::string state_hash;
};

// One course: a fresh simulation, the whole scripted path, a frame every `every` steps.
Result<Course> runCourse(const engine::Scene& scene, render::OffscreenRenderer& renderer, int every) {
  auto sim = engine::Simulation::create(scene);
  if (!sim.ok()) return Error{sim.error()};
  render::Image frame;
  engine::RunOptions options;
  options.every = every;
  options.on_frame = [&renderer, &frame](const render::RenderSnapshot& snapshot, int) -> Status {
    renderer.render(snapshot, frame);
    return {};
  };
  auto report = engine::run(**sim, options);
  if (!report.ok()) return Error{report.error()};
  Course c;
  c.wall_s = report->wall_s;
  c.step_median_us = report->step_us_median;
  c.step_p99_us = report->step_us_p99;
  c.warnings = report->warnings;
  c.perforations = report->perforations;
  c.frames = report->frames;
  c.state_hash = engine::hashHex(report->state_hash);
  sim->reset();
  c.rss_kb = residentKb();
  return c;
}

nlohmann::json summary(const std::vector<Course>& courses, double minutes) {
  nlohmann::json j;
  j["minutes"] = minutes;
  j["courses"] = nlohmann::json::array();
  for (const Course& c : courses) {
    j["courses"].push_back({{"wall_s", c.wall_s}, {"step_median_us", c.step_median_us},
                            {"step_p99_us", c.step_p99_us}, {"warnings", c.warnings},
                            {"perforations", c.perforations}, {"frames", c.frames},
                            {"rss_kb", c.rss_kb}, {"state_hash", c.state_hash}});
  }
  const Course& first = courses.front();
  const Course& last = courses.back();
  j["rss_change_pct"] = 100.0 * (static_cast<double>(last.rss_kb) / first.rss_kb - 1.0);
  j["step_p99_change_pct"] = 100.0 * (last.step_p99_us / first.step_p99_us - 1.0);
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"soak: repeat the default course for a while; memory and step time per course"};
  std::string scene_path = std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml";
  double minutes = 30.0;
  std::string out;
  app.add_option("--scene", scene_path, "Scene")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--minutes", minutes, "Wall time to keep starting courses")->check(CLI::Range(0.01, 1e4))->capture_default_str();
  app.add_option("--out", out, "JSON summary file");
  CLI11_PARSE(app, argc, argv);

  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return std::fprintf(stderr, "soak: %s\n", scene.error().c_str()), 1;
  auto renderer = render::OffscreenRenderer::create(scene->render.width, scene->render.height);
  if (!renderer.ok()) return std::fprintf(stderr, "soak: %s\n", renderer.error().c_str()), 1;
  const int every = static_cast<int>(std::lround(1.0 / scene->sim.dt));  // a frame per simulated second
  std::vector<Course> courses;
  const auto start = std::chrono::steady_clock::now();
  std::printf("course  wall s  step median us  step p99 us  warnings  rss MB  state_hash\n");
  while (courses.empty() || std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 60.0 * minutes) {
    auto course = runCourse(*scene, **renderer, every);
    if (!course.ok()) return std::fprintf(stderr, "soak: %s\n", course.error().c_str()), 1;
    courses.push_back(*course);
    std::printf("%6zu  %6.1f  %14.1f  %11.1f  %8d  %6.1f  %s\n", courses.size(), course->wall_s,
                course->step_median_us, course->step_p99_us, course->warnings, course->rss_kb / 1024.0,
                course->state_hash.c_str());
    std::fflush(stdout);
  }
  const nlohmann::json j = summary(courses, minutes);
  std::printf("rss change %.2f%% (last course against the first), step p99 change %.2f%%\n",
              j["rss_change_pct"].get<double>(), j["step_p99_change_pct"].get<double>());
  if (!out.empty()) {
    const std::string tmp = out + ".tmp";
    std::ofstream(tmp) << j.dump(2) << "\n";
    if (std::rename(tmp.c_str(), out.c_str()) != 0) return std::fprintf(stderr, "soak: cannot write %s\n", out.c_str()), 1;
  }
  return 0;
}

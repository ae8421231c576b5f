// The organ mesh cache and the progress bar shown while an organ is meshed.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <thread>

#include <pthread.h>
#include <unistd.h>

#include <CGAL/version.h>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/organ_mesh.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

// Bumped whenever the mesher's output for the same organ changes (criteria, sizing, labels),
// so that old cached meshes are not reused. With the project's and CGAL's versions it makes
// the cache key.
constexpr const char* kMesherVersion = "organ-mesher 3";

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string cacheName(const OrganSpec& organ) {
  char name[64];
  const std::string key = organKey(organ) + "|" + HYSIM_PROJECT_VERSION + "|" + kMesherVersion + "|CGAL " + CGAL_VERSION_STR;
  std::snprintf(name, sizeof name, "organ-%016llx.msh", static_cast<unsigned long long>(fnv1a(key)));
  return name;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Draws "meshing the organ [#####.....] perturbing slivers 3.2 s" on stderr from a second
// after the start until the meshing ends; a whole job on its own named thread.
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) {
    if (enabled) thread_ = std::thread(&ProgressBar::run, this);
  }
  ~ProgressBar() { finish(); }
  void setStage(MeshStage s) { stage_.store(static_cast<int>(s)); }
  void finish() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }

 private:
  void run() {
    pthread_setname_np(pthread_self(), "hysim-meshbar");
    const auto t0 = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(mutex_);
    if (wake_.wait_for(lock, std::chrono::seconds(1), [this] { return done_; })) return;
    // On a terminal the bar is redrawn in place; in a log, a line per stage.
    const bool terminal = ::isatty(::fileno(stderr)) != 0;
    int shown = -1;
    do {
      if (terminal) {
        draw(secondsSince(t0));
      } else if (stage_.load() != shown) {
        shown = stage_.load();
        std::fprintf(stderr, "meshing the organ: %s (%.1f s)\n", meshStageName(static_cast<MeshStage>(shown)),
                     secondsSince(t0));
      }
    } while (!wake_.wait_for(lock, std::chrono::milliseconds(250), [this] { return done_; }));
    if (terminal) {
      draw(secondsSince(t0));
      std::fputc('\n', stderr);
    }
  }
  void draw(double seconds) const {
    // Refinement takes about two thirds of the time, perturbation most of the rest.
    static const int kFilled[] = {2, 7, 9, 10};
    const int stage = stage_.load();
    char bar[11];
    for (int i = 0; i < 10; ++i) bar[i] = i < kFilled[stage] ? '#' : '.';
    bar[10] = '\0';
    std::fprintf(stderr, "\rmeshing the organ [%s] %-22s %5.1f s", bar, meshStageName(static_cast<MeshStage>(stage)),
                 seconds);
    std::fflush(stderr);
  }

  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::atomic<int> stage_{0};
};

// CGAL reports broken preconditions and exhausted memory by exceptions: they become errors.
Result<cutting::TetMesh> meshWithBar(const OrganSpec& organ, bool progress) {
  try {
    ProgressBar bar(progress);
    return meshOrgan(organ, [&bar](MeshStage s) { bar.setStage(s); });
  } catch (const std::exception& e) {
    return Error{std::string("meshing the organ failed: ") + e.what()};
  }
}

}  // namespace

const char* meshStageName(MeshStage stage) {
  switch (stage) {
    case MeshStage::Refine: return "refining";
    case MeshStage::Perturb: return "perturbing slivers";
    case MeshStage::Exude: return "exuding slivers";
    case MeshStage::Done: return "done";
  }
  return "";
}

std::string defaultOrganCacheDir() {
  fs::path base;
  if (const char* d = std::getenv("HYSIM_CACHE_DIR"); d != nullptr && *d != '\0') base = d;
  else if (const char* x = std::getenv("XDG_CACHE_HOME"); x != nullptr && *x != '\0') base = fs::path(x) / "hysim";
  else if (const char* h = std::getenv("HOME"); h != nullptr && *h != '\0') base = fs::path(h) / ".cache" / "hysim";
  else {
    std::error_code ec;
    const fs::path tmp = fs::temp_directory_path(ec);
    base = (ec ? fs::path("/tmp") : tmp) / "hysim-cache";
  }
  return (base / "organs").string();
}

Result<OrganMeshFile> organMeshFile(const OrganSpec& organ, const OrganMeshOptions& options) {
  const fs::path dir = options.cache_dir.empty() ? fs::path(defaultOrganCacheDir()) : fs::path(options.cache_dir);
  OrganMeshFile out;
  out.path = (dir / cacheName(organ)).string();
  std::error_code ec;
  if (options.use_cache && fs::is_regular_file(out.path, ec)) {
    out.cached = true;
    return out;
  }
  fs::create_directories(dir, ec);
  if (ec) return Error{"cannot create the organ cache folder '" + dir.string() + "': " + ec.message()};
  const auto t0 = std::chrono::steady_clock::now();
  Result<cutting::TetMesh> mesh = meshWithBar(organ, options.progress);
  if (!mesh.ok()) return Error{mesh.error()};
  out.seconds = secondsSince(t0);
  // Another process may mesh the same organ at the same time: each writes its own file.
  static std::atomic<int> serial{0};
  const std::string tmp = out.path.substr(0, out.path.size() - 4) + ".tmp" + std::to_string(::getpid()) + "-" +
                          std::to_string(serial.fetch_add(1)) + ".msh";
  if (Status st = cutting::writeMesh(tmp, *mesh); !st.ok()) {
    fs::remove(tmp, ec);
    return Error{"cannot write the organ mesh: " + st.error()};
  }
  fs::rename(tmp, out.path, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp, ec);
    return Error{"cannot move the organ mesh into '" + out.path + "': " + why};
  }
  return out;
}

}  // namespace hysim::engine

#include "app_cases.hpp"

#include <algorithm>
#include <filesystem>

#include "hysim/engine/scene.hpp"

namespace hysim::tools {
namespace {

int difficultyRank(const std::string& d) {
  if (d == "beginner") return 0;
  if (d == "intermediate") return 1;
  if (d == "advanced") return 2;
  return 3;
}

}  // namespace

std::vector<CaseInfo> listCases(const std::string& folder) {
  namespace fs = std::filesystem;
  std::vector<CaseInfo> cases;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec) || entry.path().extension() != ".yaml") continue;
    CaseInfo c;
    c.path = entry.path().lexically_normal().string();
    auto scene = engine::loadScene(c.path);
    if (scene.ok()) {
      c.name = scene->name;
      c.description = scene->description;
      c.figo_type = scene->figo_type;
      c.difficulty = scene->difficulty;
    } else {
      c.name = entry.path().stem().string();
      c.error = scene.error();
    }
    cases.push_back(c);
  }
  std::sort(cases.begin(), cases.end(), [](const CaseInfo& a, const CaseInfo& b) {
    const int ra = difficultyRank(a.difficulty), rb = difficultyRank(b.difficulty);
    return ra != rb ? ra < rb : a.name < b.name;
  });
  return cases;
}

}  // namespace hysim::tools

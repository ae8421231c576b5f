// The start screen's cases: the shipped scenes in order of difficulty, a broken one listed
// with its error.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "app_cases.hpp"
#include "test_dir.hpp"

namespace hysim::tools {
namespace {

TEST(Cases, ShippedScenesByDifficulty) {
  const std::vector<CaseInfo> cases = listCases(std::string(HYSIM_SOURCE_DIR) + "/scenes");
  std::vector<std::string> names;
  for (const CaseInfo& c : cases) {
    EXPECT_TRUE(c.error.empty()) << c.path << ": " << c.error;
    EXPECT_FALSE(c.description.empty()) << c.path;
    EXPECT_FALSE(c.figo_type.empty()) << c.path;
    names.push_back(c.name);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"diagnostic", "shaving", "default", "type2_perforation", "type2_safe"}));
  EXPECT_EQ(cases[2].difficulty, "intermediate");
  EXPECT_EQ(cases[2].figo_type, "1");
}

TEST(Cases, ABrokenSceneIsListedWithItsError) {
  const std::filesystem::path dir = testing::testDir("Cases");
  std::ofstream(dir / "broken.yaml") << "name: broken\nmesh: nowhere.msh\n";
  std::ofstream(dir / "notes.txt") << "not a scene";
  const std::vector<CaseInfo> cases = listCases(dir.string());
  ASSERT_EQ(cases.size(), 1u);
  EXPECT_EQ(cases[0].name, "broken");
  EXPECT_NE(cases[0].error.find("broken.yaml"), std::string::npos) << cases[0].error;
  EXPECT_TRUE(listCases((dir / "missing").string()).empty());
}

}  // namespace
}  // namespace hysim::tools

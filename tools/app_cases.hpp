#pragma once
// The cases a trainee can choose: the scene files of a folder, with what the start screen shows.
#include <string>
#include <vector>

namespace hysim::tools {

struct CaseInfo {
  std::string path;  // the scene file
  std::string name, description, figo_type, difficulty;
  std::string error;  // the scene does not load: why (the case is listed, not startable)
};

// Every *.yaml directly in `folder`, loaded as a scene (not meshed), ordered
// by difficulty (beginner, intermediate, advanced, unset), then name. Files that do not parse
// are listed with their error, so an instructor sees a broken case instead of a missing one.
std::vector<CaseInfo> listCases(const std::string& folder);

}  // namespace hysim::tools

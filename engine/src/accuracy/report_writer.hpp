#pragma once
// Writes the accuracy study's report.json, report.md and gnuplot PNG plots.
#include <nlohmann/json.hpp>
#include <string>

#include "hysim/cutting/result.hpp"

namespace hysim::engine::accuracy {

// "CPU model, N cores" from /proc/cpuinfo.
std::string machineDescription();

// report.json and report.md (each written to a temporary file, then renamed), and
// pareto_<case>.png / indentation.png through gnuplot (skipped with a note in report.md
// when gnuplot is missing).
Status writeStudyReport(const nlohmann::json& report, const std::string& dir, const std::string& gnuplot);

}  // namespace hysim::engine::accuracy

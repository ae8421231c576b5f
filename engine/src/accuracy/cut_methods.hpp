#pragma once
// The accuracy study's cutting section: the organ cut by the same planes with each method
// (hybrid, standard subdivision, snapping only, deletion), measured after 1, 5 and 20 cuts.
#include <nlohmann/json.hpp>

#include "hysim/engine/accuracy/cases.hpp"

namespace hysim::engine::accuracy {

// The i-th of the study's cut planes: slices across the organ (deterministic).
void cutPlane(int i, Eigen::Vector3d& point, Eigen::Vector3d& normal);

// For each method and checkpoint: elements, q*_min, minimum edge, the critical explicit step
// and the substeps it forces at 1 ms, cut time, volume error, and the sag's error under
// gravity against standard subdivision's (the geometrically exact cut body), R1 on both.
nlohmann::json cutMethodStudy(const AccuracyCase& organ, const Scene& scene, const std::vector<int>& checkpoints);

}  // namespace hysim::engine::accuracy

#pragma once
// A picture of a generated organ's section (hysim mesh --section): the plane through the
// cavity's long axis and the first myoma's centre, coloured by material, the band meshed
// finely shaded darker. Drawn from the organ's parameters, before any meshing: the pictures of
// the FIGO types in scenes/README.md.
#include "hysim/engine/organ.hpp"
#include "hysim/render/image.hpp"

namespace hysim::tools {

render::Image drawOrganSection(const engine::OrganSpec& organ, int width);

}  // namespace hysim::tools

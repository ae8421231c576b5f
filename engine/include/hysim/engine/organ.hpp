#pragma once
// A parametric organ: the uterus (a distended cavity inside a wall, a cervical canal) and its
// myomas, described by an instructor in the scene's `organ:` section and meshed at load
// (organ_mesh.hpp). This file holds the geometry only: where each myoma sits for its FIGO type,
// which material a point belongs to, how fine the mesh must be there, and the checks that
// refuse an organ that cannot be built. Frame as the pre-meshed assets: z the long axis
// (cervix at -z, fundus at +z), y anterior, x the patient's left; the cavity's centre at 0.
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "hysim/cutting/mesh.hpp"

namespace hysim::engine {

enum class MyomaWall { Anterior, Posterior, Left, Right, Fundal };

struct MyomaSpec {
  std::string figo = "1";      // "0".."7" or "2-5"
  double diameter_mm = 16.0;
  MyomaWall wall = MyomaWall::Posterior;
  double angle_deg = 0.0;      // about the long axis from the wall's middle (fundal: tilt towards anterior)
  double height = 0.0;         // along the cavity, -1 (cervix) .. 1 (fundus); not used for fundal
  double young_modulus_kpa = 150.0;
  // Centre's signed distance from the endometrium along the wall's normal (+ into the wall);
  // NaN: the FIGO type's own (myomaOffsetMm).
  double offset_mm = std::numeric_limits<double>::quiet_NaN();
};

struct UterusSpec {
  Eigen::Vector3d cavity_semi_axes_mm{16, 11, 24};
  double wall_mm = 12.0;
  double canal_radius_mm = 3.5;
  double myometrium_kpa = 60.0;
  double anchored_depth_mm = 3.0;  // the outer layer held by the surrounding tissue
};

struct OrganMeshSizes {
  double fine_mm = 1.5;    // in and within `fine_band_mm` of every myoma
  double coarse_mm = 4.0;  // the far wall
  double fine_band_mm = 3.0;
};

struct OrganSpec {
  UterusSpec uterus;
  std::vector<MyomaSpec> myomas;
  OrganMeshSizes mesh;
  bool given = false;  // the scene has an `organ:` section
};

// Material labels of a generated mesh: the wall, then one per myoma in the order given.
constexpr int kWallLabel = 1;
constexpr int kFirstMyomaLabel = 2;

// A myoma placed: its sphere, its stalk (types 0 and 7) and where it meets the wall.
struct PlacedMyoma {
  Eigen::Vector3d centre{0, 0, 0};
  double radius_mm = 0.0;
  Eigen::Vector3d base{0, 0, 0};    // the endometrium point under the myoma
  Eigen::Vector3d normal{0, 0, 1};  // the cavity's outward normal there (into the wall)
  bool stalk = false;
  Eigen::Vector3d stalk_from{0, 0, 0}, stalk_to{0, 0, 0};
  double stalk_radius_mm = 0.0;
};

std::vector<PlacedMyoma> placeMyomas(const OrganSpec& organ);
// The centre's offset from the endometrium (+ into the wall) a FIGO type gives a myoma.
double myomaOffsetMm(const MyomaSpec& m, const UterusSpec& u);

// 0 outside the organ, kWallLabel in the wall, kFirstMyomaLabel + k in myoma k.
int organLabel(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed, const Eigen::Vector3d& p);
// The wanted edge length at p: fine near the myomas, growing linearly to coarse.
double organSizeAt(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed, const Eigen::Vector3d& p);
// How far the ray from `from` (inside the ellipsoid with semi-axes `semi`, centred at the
// origin) along the unit `d` goes before it leaves it, mm.
double ellipsoidExitMm(const Eigen::Vector3d& from, const Eigen::Vector3d& d, const Eigen::Vector3d& semi);
// Outer ellipsoid semi-axes (the serosa without subserosal myomas).
Eigen::Vector3d outerSemiAxes(const UterusSpec& u);
// Radius of a sphere about the origin that holds the whole organ.
double organBoundingRadius(const OrganSpec& organ, const std::vector<PlacedMyoma>& placed);

// One reason an organ cannot be built: `myoma` the index (-1: the uterus or the mesh sizes),
// `key` the scene key to point at.
struct OrganProblem {
  int myoma = -1;
  std::string key;
  std::string message;
};
std::vector<OrganProblem> checkOrgan(const OrganSpec& organ);

// Per myoma, the thinnest wall left between the tissue's surface and the serosa under the
// myoma's footprint (a cylinder of its radius along its normal), measured along the normal in
// `mesh`'s rest positions: after a resection, the wall behind the crater. NaN for a myoma with
// no surface under it.
std::vector<double> wallBehindMyomasMm(const OrganSpec& organ, const cutting::TetMesh& mesh);

// Every parameter that shapes the mesh, printed exactly (the cache's key).
std::string organKey(const OrganSpec& organ);

std::string wallName(MyomaWall w);

}  // namespace hysim::engine

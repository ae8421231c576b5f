#pragma once
// Mass-spring tissue model. A scene compiles to a Model (what does not change while
// stepping); everything that changes lives in State (MuJoCo's mjModel / mjData split).
//
// Units (consistent, so no conversion factors appear in the step):
//   length mm, mass g, time s  =>  force g*mm/s^2 = 1 uN, stiffness g/s^2 (= mN/m),
//   pressure / Young's modulus g/(mm*s^2) = 1 Pa, density g/mm^3 (1 g/cm^3 = 1e-3 g/mm^3).
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "hysim/cutting/mesh.hpp"

namespace hysim::sim {

struct Material {
  std::string name;
  int label = 0;                      // element label in the mesh (Gmsh physical tag)
  double young_modulus_pa = 60e3;     // E; myometrium ~30-90 kPa, fibroids ~60-220 kPa
  double density_g_mm3 = 1.05e-3;     // rho; soft tissue ~1.05 g/cm^3
  double stiffness_damping_s = 0.0;   // beta: spring damping c = beta * k (Rayleigh, stiffness part)
};

enum class Integrator {
  SymplecticEuler,  // semi-implicit Euler, explicit springs, `substeps` per step
  ImplicitEuler,    // backward Euler, local/global iterations on a prefactored sparse matrix
  Xpbd,             // XPBD (Macklin 2016) in small substeps (Macklin 2019): springs as compliant
                    // distance constraints, Gauss-Seidel; stable for any substep, no factorisation
};

struct ModelOptions {
  double dt = 1e-3;                            // s, fixed step
  Integrator integrator = Integrator::SymplecticEuler;
  int substeps = 0;                            // symplectic Euler; 0 = choose from the stability limit
  int max_substeps = 32;                       // automatic substeps never exceed this (symplectic: mass scaling)
  double stability_safety = 0.85;               // substep = safety * critical step when automatic
  int implicit_iterations = 8;                 // local/global iterations per implicit step
  // XPBD substeps per step; 0 = the count symplectic Euler's stability limit asks for (with
  // stability_safety, capped at max_substeps) but without mass scaling: XPBD is stable at any
  // substep, fewer only cost accuracy (numerical damping, and springs that act softer by
  // about (h omega)^2 when the Gauss-Seidel sweeps have not converged).
  int xpbd_substeps = 0;
  int xpbd_iterations = 1;                     // Gauss-Seidel sweeps over the springs per XPBD substep
  double drag_per_s = 0.0;                     // alpha: mass-proportional damping (fluid drag), 1/s
  Eigen::Vector3d gravity{0.0, 0.0, -9810.0};  // mm/s^2
  double max_speed_mm_s = 1e5;                 // a node faster than this is numerical trouble
  bool simd = true;                            // AVX2 spring loop where the CPU has it (same results)
};

class ImplicitSolver;  // prefactored system of the implicit integrator (step.cpp)

// Per-node vectors (#N x 3). Row-major: a node's x, y, z are adjacent, so a spring touches
// two cache lines per array instead of six (the step is bound by these gathers).
using NodeVectors = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The springs the explicit step evaluates (those with at least one free end), laid out for
// it: structure-of-arrays so the force loop vectorises, and each node's incident springs in
// compressed rows so forces are summed per node in a fixed order (no scatter, deterministic).
// Derived from Model's spring arrays by buildModel; those arrays stay the reference.
struct StepSprings {
  std::vector<std::int32_t> a, b;      // #M node indices
  std::vector<double> rest_length;     // #M, mm
  std::vector<double> stiffness;       // #M, g/s^2
  std::vector<double> damping;         // #M, g/s
  std::vector<std::int32_t> node_offset;  // #N+1: node i's incident springs are entries [off[i], off[i+1])
  std::vector<std::int32_t> incident;     // #2M spring index
  std::vector<double> sign;               // #2M: +1 where the node is the spring's a end, -1 at b
  int size() const { return static_cast<int>(a.size()); }
};

struct Model {
  using SpringIndex = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2>;

  int num_nodes = 0;
  Eigen::VectorXd mass;            // #N, g (lumped: a quarter of each incident tet's mass)
  Eigen::VectorXd inv_mass;        // #N, 1/g; 0 for fixed nodes
  SpringIndex springs;             // #S x 2 node indices, one spring per unique tet edge
  Eigen::VectorXd rest_length;     // #S, mm
  Eigen::VectorXd stiffness;       // #S, g/s^2: Van Gelder k = sum_t E_t V_t / |e|^2
  Eigen::VectorXd damping;         // #S, g/s: c = beta * k
  std::vector<std::uint8_t> fixed; // #N, 1 = anchored (never moves)
  StepSprings step_springs;          // the springs above that can move, for the explicit step
  std::vector<Material> materials;

  ModelOptions options;
  double substep = 0.0;            // s, the integrator's substep (dt / substeps); implicit Euler: unused
  int substeps = 1;                // symplectic Euler's, or XPBD's (options.xpbd_substeps or its rule)
  double critical_dt = 0.0;        // s, estimated stability limit of symplectic Euler
  double omega_max = 0.0;          // rad/s, estimated highest natural frequency
  double added_mass = 0.0;         // g, added by selective mass scaling to respect max_substeps
  // #N x 3: the estimate of the highest mode behind omega_max (M^1/2-scaled displacements, unit
  // norm, zero at fixed nodes). A cut that leaves it alone leaves omega_max valid away from
  // the cut, so the incremental update (updateModelAfterCut3D) only estimates near the cut.
  Eigen::MatrixX3d stability_mode;
  // Updates since omega_max was last a Lanczos estimate over all free nodes in which it is a
  // previous estimate held as a bound (its mode was near a cut; see updateModelAfterCut3D).
  // -1: no such estimate yet (buildModel's power iteration approaches omega_max from below,
  // too far to serve as a bound).
  int stability_held = -1;

  std::shared_ptr<const ImplicitSolver> implicit;  // set when integrator == ImplicitEuler
};

// 64-byte aligned storage for the step's vector loads; no zero fill on resize.
template <class T>
struct AlignedAllocator {
  using value_type = T;
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64))); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, std::align_val_t(64)); }
  // resize() leaves new elements uninitialised (they are written before they are read).
  template <class U>
  void construct(U*) noexcept {}
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const AlignedAllocator<U>&) const { return false; }
};

struct State {
  NodeVectors x;        // #N x 3 positions, mm
  NodeVectors v;        // #N x 3 velocities, mm/s
  NodeVectors f;        // #N x 3 force accumulator, uN
  NodeVectors scratch0; // #N x 3 integrator scratch (sized when the model is built)
  NodeVectors scratch1; // #N x 3
  NodeVectors scratch2; // #N x 3
  // #M x 4 (x, y, z, 0), rows 32-byte aligned: force of each step spring on its a end (one
  // 32-byte load per incident spring when the forces are summed per node)
  std::vector<double, AlignedAllocator<double>> spring_force;
  std::vector<double> xpbd_lambda;  // #S: XPBD's accumulated constraint impulse per spring (Model::springs)
  Eigen::MatrixX3d solve0;  // #N x 3 column-major: the sparse triangular solves work in place
  Eigen::MatrixX3d solve1;  // on column-major right-hand sides without temporaries
  std::uint64_t steps = 0;
  double time = 0.0;         // s, steps * dt (never read from a clock)
  int warnings = 0;          // numerical trouble events (divergence); the step never throws
  bool diverged = false;     // once set, the step leaves the state untouched
};

struct StepInput {
  const NodeVectors* external_force = nullptr;  // #N x 3 uN (contact), or null
  // Optional: called with the current positions and velocities before each substep's forces
  // (symplectic Euler and XPBD; once per step for implicit Euler), to refresh *external_force, e.g.
  // contact that follows the tissue within the step. A plain function pointer: no allocation.
  void (*refresh_external)(void* context, const NodeVectors& x, const NodeVectors& v) = nullptr;
  void* context = nullptr;
};

// Builds the model. `fixed_nodes` are anchored at their rest positions. Materials are looked
// up by the mesh's element labels; an element label with no material is an error.
Result<Model> buildModel(const cutting::TetMesh& mesh, const std::vector<Material>& materials,
                         const std::vector<int>& fixed_nodes, const ModelOptions& options);

// Rest state: x = mesh positions, v = 0, f = 0; scratch and spring forces sized (not zeroed:
// the step writes them before it reads them).
State makeState(const Model& model, const cutting::TetMesh& mesh);
// Sizes the state's per-step arrays for the model: f zeroed (it stays zero at anchored nodes,
// the symplectic step writes free rows only); the integrators' scratch arrays and the spring
// forces only sized, as every step writes them before it reads them.
void sizeStepArrays(const Model& model, State& state);

// Advances the state by one fixed step dt. Allocates nothing; never throws. Non-finite
// values or speeds above options.max_speed_mm_s count a warning and freeze the state.
void step(const Model& model, State& state, const StepInput& input);

// Energies (for tests and reports), g*mm^2/s^2 = nJ.
double kineticEnergy(const Model& model, const State& state);
double springEnergy(const Model& model, const State& state);

// 64-bit FNV-1a hash over the bytes of x and v: equal states hash equal; bitwise.
std::uint64_t stateHash(const State& state);

}  // namespace hysim::sim

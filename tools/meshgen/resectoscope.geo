// Resectoscope tip (outer sheath + cutting loop electrode), surface mesh for hysim.
// Regenerate with: tools/make-tool-mesh  (writes assets/resectoscope.stl)
//
// Units: millimetres. Body frame: the scope tip / camera is at the origin looking
// along +z; the shaft lies behind it (z < 0); +y is "up" in the camera image, the
// cutting loop hangs below the axis (-y).
// Written for Gmsh 4.8 (Debian 12); OpenCASCADE kernel.
//
// Cutting loop parameters (the engine's loop-electrode model uses the same numbers):
//   arms:  two straight wires, radius arm_r = 0.4, axis parallel to z, from z = 0
//          (shaft front face) to z = loop_z = 12, at x = +-loop_R = +-3.5, y = loop_y = -3;
//   loop:  semicircular wire (torus segment), tube radius wire_r = 0.3, loop radius
//          loop_R = 3.5, centre (0, loop_y, loop_z) = (0, -3, 12), in the plane z = 12,
//          spanning angles pi..2pi about that centre (from (-3.5, -3, 12) through the
//          lowest point (0, -6.5, 12) to (3.5, -3, 12)): it opens towards +y (the arms)
//          and its cutting edge faces +z (forward) when the loop sweeps back (-z).
//   joints: spheres of radius arm_r at (+-3.5, -3, 12) round off arm/loop junctions.
//   Note: the arms lie just outside the sheath (axis distance sqrt(3.5^2 + 3^2) = 4.61
//   > shaft_r + arm_r), so arms and sheath are separate closed surfaces.

SetFactory("OpenCASCADE");
Geometry.OCCBoundsUseStl = 1;

// ---- parameters -----------------------------------------------------------
shaft_r = 4.0;      // 26 Fr outer sheath (8.7 mm diameter), rounded to 8 mm
shaft_len = 60;     // shaft from z = 0 back to z = -shaft_len
arm_r = 0.4;        // electrode arm wire radius
wire_r = 0.3;       // cutting loop wire radius
loop_R = 3.5;       // cutting loop radius (= arm half spacing in x)
loop_y = -3;        // arm / loop-centre height
loop_z = 12;        // loop plane

// ---- geometry -------------------------------------------------------------
Cylinder(1) = {0, 0, -shaft_len, 0, 0, shaft_len, shaft_r};
Cylinder(2) = { loop_R, loop_y, 0, 0, 0, loop_z, arm_r};
Cylinder(3) = {-loop_R, loop_y, 0, 0, 0, loop_z, arm_r};
Sphere(4) = { loop_R, loop_y, loop_z, arm_r};
Sphere(5) = {-loop_R, loop_y, loop_z, arm_r};
// Torus(tag) = {centre, main radius, tube radius, sweep angle}: axis along z,
// swept from angle 0 (+x) through +y to pi; turned by pi about its axis so it
// spans pi..2pi (through -y).
Torus(6) = {0, loop_y, loop_z, loop_R, wire_r, Pi};
Rotate {{0, 0, 1}, {0, loop_y, loop_z}, Pi} { Volume{6}; }

electrode() = BooleanUnion{ Volume{2}; Delete; }{ Volume{3, 4, 5, 6}; Delete; };

// ---- mesh size ------------------------------------------------------------
Mesh.MeshSizeFromCurvature = 16;  // ~16 segments per full circle (shaft), clamped by MeshSizeMin on the wires
Mesh.MeshSizeMin = 0.3;
Mesh.MeshSizeMax = 3.0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeExtendFromBoundary = 1;

General.NumThreads = 1;
Mesh.MaxNumThreads1D = 1; Mesh.MaxNumThreads2D = 1;
Mesh.RandomSeed = 1;
Mesh.Algorithm = 6;       // Frontal-Delaunay (2D)

// ---- output: all surface triangles, one STL solid, binary --------------------
Mesh.SaveAll = 1;
Mesh.Binary = 1;          // binary STL: ~5x smaller than ASCII
Mesh.StlOneSolidPerSurface = 0;

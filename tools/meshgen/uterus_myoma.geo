// Uterus with a FIGO type 1 submucous myoma, for hysim.
// Regenerate with: tools/make-uterus-mesh  (writes assets/uterus_myoma.msh)
//
// Units: millimetres. Frame: z = uterine long axis (cervix -z, fundus +z),
//        y = anterior (+) / posterior (-), x = left / right. Origin = cavity centre.
// Physical volumes (material tags): 1 = myometrium (wall), 2 = myoma (whole sphere).
// Only tetrahedra of the physical volumes are written (no surface elements).
// Written for Gmsh 4.8 (Debian 12); OpenCASCADE kernel.

SetFactory("OpenCASCADE");
Geometry.OCCBoundsUseStl = 1;

// ---- parameters -----------------------------------------------------------
cav_a = 16; cav_b = 11; cav_c = 24;    // distended cavity, ellipsoid semi-axes (x, y, z)
out_a = 28; out_b = 23; out_c = 36;    // outer uterine surface, ellipsoid semi-axes
canal_r = 3.5;                          // cervical canal radius
canal_z0 = -40; canal_z1 = -20;         // canal runs along z from z0 to z1 (through the wall)
// Myoma centre and radius. The defaults give the FIGO type 1 myoma of assets/uterus_myoma.msh;
// `gmsh -setnumber myo_y V -setnumber myo_r V` overrides them (tools/make-uterus-mesh --figo 2).
myo_x = 0; myo_z = 4;
DefineConstant[ myo_y = -9 ];           // posterior wall, ~6 mm of the type 1 myoma embedded
DefineConstant[ myo_r = 8 ];

// The simulator's explicit substep is set by the highest natural frequency of the
// mass-spring network, ~ sqrt(E / rho) / (local edge length). The myoma is 2.5x stiffer
// than the wall (150 vs 60 kPa, wave speed 1.55x), so it gets the larger elements; a
// nearly uniform size everywhere else keeps short edges away and still gives ~12k tets.
h_fine   = 2.7;   // target edge length at the cavity, canal and myoma surfaces
h_myo    = 2.8;   // target edge length in a ball of radius myo_r + 1 around the myoma
h_coarse = 4.0;   // target edge length towards the outer surface
d_fine   = 1.0;   // distance from the cavity/myoma surface where growth starts
d_coarse = 14.0;  // distance where h_coarse would be reached (the wall is ~12 mm: ~3.8 mm at the outer surface)

// ---- geometry -------------------------------------------------------------
// Ellipsoids = unit spheres, turned so that their poles lie on the x axis and
// their seam (a half meridian) runs over the anterior side (y > 0, z = 0), away
// from the canal (which pierces the cavity at its -z apex) and from the myoma
// (posterior), then scaled. Poles or seams crossing the cut-outs at grazing
// angles give short curves and sliver tets.
Sphere(1) = {0, 0, 0, 1};
Rotate {{0, 1, 0}, {0, 0, 0}, Pi/2} { Volume{1}; }
Rotate {{1, 0, 0}, {0, 0, 0}, Pi/2} { Volume{1}; }
Dilate {{0, 0, 0}, {out_a, out_b, out_c}} { Volume{1}; }

Sphere(2) = {0, 0, 0, 1};
Rotate {{0, 1, 0}, {0, 0, 0}, Pi/2} { Volume{2}; }
Rotate {{1, 0, 0}, {0, 0, 0}, Pi/2} { Volume{2}; }
Dilate {{0, 0, 0}, {cav_a, cav_b, cav_c}} { Volume{2}; }

Cylinder(3) = {0, 0, canal_z0, 0, 0, canal_z1 - canal_z0, canal_r};

// Myoma: poles turned onto the y axis (deepest point in the wall, top of the
// bulge), so its seam crosses the wall/cavity intersection once, transversally.
Sphere(4) = {myo_x, myo_y, myo_z, myo_r};
Rotate {{1, 0, 0}, {myo_x, myo_y, myo_z}, Pi/2} { Volume{4}; }

// Wall = outer - cavity - canal.
wall() = BooleanDifference{ Volume{1}; Delete; }{ Volume{2, 3}; Delete; };
// Fragment wall and myoma: conforming interface; the myoma falls into its
// embedded part and its bulging part (both material 2), the wall keeps the rest.
frag() = BooleanFragments{ Volume{wall()}; Delete; }{ Volume{4}; Delete; };

eps = 0.1;   // bounding boxes come from an STL approximation (Geometry.OCCBoundsUseStl): allow slack
myoma() = Volume In BoundingBox {myo_x - myo_r - eps, myo_y - myo_r - eps, myo_z - myo_r - eps,
                                 myo_x + myo_r + eps, myo_y + myo_r + eps, myo_z + myo_r + eps};
wallv() = frag();
wallv() -= myoma();

If (#wallv() != 1 || #myoma() != 2)
  Error("uterus_myoma.geo: expected 1 wall and 2 myoma volumes after fragmenting, got %g and %g", #wallv(), #myoma());
  Abort;
EndIf

Physical Volume("myometrium", 1) = {wallv()};
Physical Volume("myoma", 2) = {myoma()};

// ---- mesh size ------------------------------------------------------------
// h_fine at the cavity surface, the canal and the myoma surface, growing into the wall
// towards h_coarse; exactly h_myo inside a ball around the myoma (Max(Min(threshold, ball
// with h_myo inside), ball with h_myo inside and 0 outside)).
inner() = Surface In BoundingBox {-cav_a - eps, -cav_b - eps, -cav_c - eps,
                                   cav_a + eps,  cav_b + eps,  cav_c + eps};
myos() = Surface In BoundingBox {myo_x - myo_r - eps, myo_y - myo_r - eps, myo_z - myo_r - eps,
                                 myo_x + myo_r + eps, myo_y + myo_r + eps, myo_z + myo_r + eps};
canals() = Surface In BoundingBox {-canal_r - eps, -canal_r - eps, canal_z0 - eps,
                                     canal_r + eps,  canal_r + eps, canal_z1 + eps};
If (#inner() != 3 || #myos() != 3 || #canals() != 1)
  Error("uterus_myoma.geo: surface lookup found %g cavity, %g myoma, %g canal surfaces (expected 3, 3, 1)", #inner(), #myos(), #canals());
  Abort;
EndIf
// Myoma surfaces: Frontal-Delaunay. MeshAdapt left ~1.1 mm edges around the sphere pole at
// the top of the bulge (the stiffest nodes of the model). The ellipsoids keep MeshAdapt.
MeshAlgorithm Surface{myos()} = 6;

Field[1] = Distance;
Field[1].SurfacesList = {inner(), myos(), canals()};
Field[1].NNodesByEdge = 200;

Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_fine;
Field[2].SizeMax = h_coarse;
Field[2].DistMin = d_fine;
Field[2].DistMax = d_coarse;

Field[3] = Ball;
Field[3].XCenter = myo_x; Field[3].YCenter = myo_y; Field[3].ZCenter = myo_z;
Field[3].Radius = myo_r + 1;
Field[3].Thickness = 2;
Field[3].VIn = h_myo;
Field[3].VOut = 1000;

Field[5] = Ball;
Field[5].XCenter = myo_x; Field[5].YCenter = myo_y; Field[5].ZCenter = myo_z;
Field[5].Radius = myo_r + 1;
Field[5].Thickness = 2;
Field[5].VIn = h_myo;
Field[5].VOut = 0;

Field[4] = Min;
Field[4].FieldsList = {2, 3};
Field[6] = Max;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeMax = Max(h_coarse, h_myo);

// ---- meshing options (fixed for determinism) -------------------------------
General.NumThreads = 1;
Mesh.MaxNumThreads1D = 1; Mesh.MaxNumThreads2D = 1; Mesh.MaxNumThreads3D = 1;
Mesh.RandomSeed = 1;
Mesh.Algorithm = 1;        // MeshAdapt (2D): on these BSpline ellipsoids it gives the best surface
                           // triangles near the sphere poles (Frontal-Delaunay left slivers there);
                           // the myoma surfaces use Frontal-Delaunay (MeshAlgorithm above)
Mesh.Algorithm3D = 1;      // Delaunay (3D)
Mesh.Optimize = 1;
// Mesh.OptimizeNetgen is not used: Debian's gmsh 4.8.4 is built without Netgen.
Mesh.OptimizeThreshold = 0.5;  // optimise every tet with gamma < 0.5 (gamma = 3 q*)

// ---- output ---------------------------------------------------------------
Mesh.MshFileVersion = 2.2;
Mesh.Binary = 0;
Mesh.SaveAll = 0;

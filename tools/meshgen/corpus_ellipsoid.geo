// Ellipsoid 30 x 22 x 18 mm (semi-axes) for the mesh corpus (tools/make-corpus).
// Uniform target size h (gmsh -setnumber h V); tets only, physical volume 1.
// Written for Gmsh 4.8 (Debian 12); OpenCASCADE kernel.
SetFactory("OpenCASCADE");
DefineConstant[ h = 4.5 ];
Sphere(1) = {0, 0, 0, 1};
Dilate {{0, 0, 0}, {30, 22, 18}} { Volume{1}; }
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Physical Volume(1) = {1};

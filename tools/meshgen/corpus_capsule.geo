// Capsule for the mesh corpus (tools/make-corpus): a cylinder of radius 10 mm and length
// 30 mm along z with hemispherical ends (50 mm in all). Uniform target size h
// (gmsh -setnumber h V); tets only, physical volume 1.
// Written for Gmsh 4.8 (Debian 12); OpenCASCADE kernel.
SetFactory("OpenCASCADE");
DefineConstant[ h = 2.5 ];
r = 10; len = 30;
Cylinder(1) = {0, 0, -len / 2, 0, 0, len, r};
Sphere(2) = {0, 0, -len / 2, r};
Sphere(3) = {0, 0, len / 2, r};
BooleanUnion(4) = { Volume{1}; Delete; }{ Volume{2, 3}; Delete; };
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Physical Volume(1) = {4};

// Table 2 test mesh (hysim tables --table 2): an ellipsoid with semi-axes 20, 15, 12 mm meshed
// coarsely, like the paper's small mesh (59 nodes, 135 tets with Gmsh 4.8.4). Regenerate:
//   gmsh tests/data/cutting/table2_ellipsoid.geo -3 -nt 1 -format msh22 -save_all 0 -o tests/data/cutting/table2_ellipsoid.msh
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Dilate {{0, 0, 0}, {20, 15, 12}} { Volume{1}; }
Mesh.CharacteristicLengthMin = 8.5;
Mesh.CharacteristicLengthMax = 8.5;
Mesh.Optimize = 1;
Physical Volume(1) = {1};

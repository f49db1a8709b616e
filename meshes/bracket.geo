// Angle bracket with three bores: the sample part of the quick start. Lengths in millimetres.
// A 90 x 40 x 8 base plate, a 8 x 40 x 60 upright, a 10 mm rib radius at the inner corner, two
// 10 mm bores through the base and one 12 mm bore through the upright.
// make_bracket_cad.sh turns it into bracket.step (STEP, declared in mm) and bracket.brep with gmsh.
SetFactory("OpenCASCADE");

Box(1) = {0, 0, 0, 90, 40, 8};       // base plate
Box(2) = {0, 0, 0, 8, 40, 60};       // upright
Box(3) = {8, 0, 8, 10, 40, 10};      // corner block, cut by a cylinder below to a fillet
Cylinder(4) = {18, -1, 18, 0, 42, 0, 10};
fillet() = BooleanDifference{ Volume{3}; Delete; }{ Volume{4}; Delete; };
body() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2, fillet()}; Delete; };

Cylinder(10) = {45, 20, -1, 0, 0, 10, 5};   // bore 1, diameter 10
Cylinder(11) = {75, 20, -1, 0, 0, 10, 5};   // bore 2, diameter 10
Cylinder(12) = {-1, 20, 42, 10, 0, 0, 6};   // bore 3 (upright), diameter 12
BooleanDifference{ Volume{body()}; Delete; }{ Volume{10, 11, 12}; Delete; }

// The connecting rod in its own frame, lengths in mm: a 6 mm high, 10 mm thick aluminium bar between two eyes
// 250 mm apart along x, each with an 8 mm bore along z (at x = 0 and x = 250). It bends in the mechanism's plane
// (x-y) about its 6 mm height; the 10 mm thickness keeps it stiff out of that plane.
SetFactory("OpenCASCADE");
L = 250;   // bore to bore
Box(1) = {0, -3, 0, L, 6, 10};
Cylinder(2) = {0, 0, 0, 0, 0, 10, 8};        // eye at the crank end
Cylinder(3) = {L, 0, 0, 0, 0, 10, 8};        // eye at the slider end
rod() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2, 3}; Delete; };
Cylinder(4) = {0, 0, -1, 0, 0, 12, 4};       // the bores, 8 mm across
Cylinder(5) = {L, 0, -1, 0, 0, 12, 4};
BooleanDifference{ Volume{rod()}; Delete; }{ Volume{4, 5}; Delete; }

// The crank in its own frame, lengths in mm: an arm 10 mm thick (z from -10 to 0, below the rod) from its shaft
// at the origin to its pin at x = 50. A rigid body in the scene (modes: rigid): only its mass properties matter.
SetFactory("OpenCASCADE");
Box(1) = {0, -8, -10, 50, 16, 10};
Cylinder(2) = {0, 0, -10, 0, 0, 10, 15};     // the boss round the shaft
Cylinder(3) = {50, 0, -10, 0, 0, 10, 8};     // the round end at the pin
BooleanUnion{ Volume{1}; Delete; }{ Volume{2, 3}; Delete; }

// The slider (crosshead) in its own frame, lengths in mm: a steel block 40 x 20 x 10 centred on its pin at the
// origin (z from 0 to 10, level with the rod). A rigid body in the scene.
SetFactory("OpenCASCADE");
Box(1) = {-20, -10, 0, 40, 20, 10};

// A steel-beam-sized box, 1 x 0.05 x 0.05, with coordinates in metres.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.05, 0.05};

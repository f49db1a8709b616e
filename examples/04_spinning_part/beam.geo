// A slender steel cantilever (a blade, much simplified), lengths in m: 1 m long along x, 30 mm wide (y), 20 mm
// thick (z). Its root face at x = 0 goes on the hub.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.03, 0.02};

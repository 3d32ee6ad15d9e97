// Stiffened cylindrical panel for data/structures/curved_panel/curved_panel.toml.
// Regenerate the mesh with `python make_mesh.py` (Gmsh Python API, `pip install gmsh`)
// or `gmsh -2 -format msh22 curved_panel.geo -o curved_panel.msh`.
// Radius 0.5 m, 60 degree arc in the y-z plane centred on z, 0.4 m long along x;
// 20 x 16 first-order quads (transfinite, recombined). Physical groups: "skin" (2-D),
// "stiffener" (1-D, the mid-arc line along x, shared by the two skin halves so that the
// stiffener's line elements use the skin's nodes) and "ends" (1-D, the curved edges).
R = 0.5;
L = 0.4;
HALF_ARC = 30 * Pi / 180;
NX = 20;             // elements along x
NA = 16;             // elements around the arc (8 on each side of the stiffener)

Point(1) = {0, 0, 0};                                   // arc centre at x = 0
Point(2) = {0, -R * Sin(HALF_ARC), R * Cos(HALF_ARC)};
Point(3) = {0, 0, R};
Point(4) = {0, R * Sin(HALF_ARC), R * Cos(HALF_ARC)};
Point(5) = {L, 0, 0};                                   // arc centre at x = L
Point(6) = {L, -R * Sin(HALF_ARC), R * Cos(HALF_ARC)};
Point(7) = {L, 0, R};
Point(8) = {L, R * Sin(HALF_ARC), R * Cos(HALF_ARC)};

Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {6, 5, 7};
Circle(4) = {7, 5, 8};
Line(5) = {2, 6};
Line(6) = {3, 7};    // the stiffener line
Line(7) = {4, 8};

Curve Loop(1) = {5, 3, -6, -1};
Surface(1) = {1};
Curve Loop(2) = {6, 4, -7, -2};
Surface(2) = {2};

Transfinite Curve {1, 2, 3, 4} = NA / 2 + 1;
Transfinite Curve {5, 6, 7} = NX + 1;
Transfinite Surface {1, 2};
Recombine Surface {1, 2};

Physical Surface("skin") = {1, 2};
Physical Curve("stiffener") = {6};
Physical Curve("ends") = {1, 2, 3, 4};

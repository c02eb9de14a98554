// The specimen of cases/first-case, written with gmsh's OpenCASCADE kernel and exported as
// STEP (docs/tutorial.md): gmsh plate.geo -0 -o plate.step
// A plate 60 x 40 x 5 mm (lengths in mm: the STEP file says so) with a 10 mm hole through
// its centre.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 40, 5};
Cylinder(2) = {30, 20, -1, 0, 0, 7, 5};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };

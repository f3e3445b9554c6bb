// CalculiX (ccx) as an independent check of the reference FEM (DESIGN 5), for the tests
// (fem/calculix_test.cpp): writes an input deck for a phymul::fem problem, runs ccx on it
// and reads the nodal results back.
//
// The reference law is CalculiX's *HYPERELASTIC, NEO HOOKE
//   U = C10 (I1bar - 3) + 1/D1 (J - 1)^2,  C10 = mu / 2,  D1 = 2 / K,
//   mu = E / (2 (1 + nu)),  K = E / (3 (1 - 2 nu)),
// which is exactly phymul's Law::neo_hookean (W = mu/2 (I1bar - 3) + kappa/2 (J - 1)^2),
// solved with NLGEOM. CalculiX's *ELASTIC under NLGEOM would be St-Venant-Kirchhoff, so it
// is only written for Law::linear, without NLGEOM.
//
// Elements: hexahedra become `element` (C3D8I by default: incompatible modes, which do not
// lock at nu = 0.499 like plain C3D8 does; CalculiX 2.20 has no hybrid C3D8H), tetrahedra
// C3D4 and wedges C3D6. CalculiX's C3D8 and C3D4 node orders are VTK's; VTK's wedge has its
// first triangle facing away from the second, CalculiX's towards it, so wedges are written
// as (0, 2, 1, 3, 5, 4).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"

namespace phymul::fem {

// The input deck (.inp) of the static problem: one *STEP reaching the prescribed values at
// time 1 (ramped). Nodes are numbered 1..n in mesh order (CalculiX id = phymul index + 1).
// Node sets: NALL (every node), NCONS (every node with a prescribed component), and the
// mesh's own node sets (upper case, other characters than letters, digits and '_' become
// '_'). Neo-Hookean: NLGEOM, *STATIC with initial and largest increment 1 / increments,
// cutbacks down to 1e-5 of it, and Newton tolerances tightened from ccx's defaults (0.5 %
// residual, 1 % correction) to 1e-6 and 1e-5 by *CONTROLS. Real numbers are written in at
// most 20 characters (ccx reads them as Fortran f20.0). Printed to the .dat file: U of
// NALL, RF of NCONS.
// Throws std::invalid_argument for a mesh that is not volumetric (or fails validate()), an
// element that is not C3D8, C3D8I or C3D8R, a material out of range (E > 0,
// -1 < nu < 0.5), a prescribed node or axis out of range, a component prescribed twice,
// a non-finite value, or increments < 1.
std::string calculix_deck(const Mesh& mesh, const Material& material,
                          const std::vector<Dirichlet>& prescribed, int increments,
                          const std::string& element = "C3D8I");

struct CalculixResult {
  bool ok = false;
  std::string message;             // why not ok (with the tail of ccx's log); empty when ok
  std::vector<Vec3> displacement;  // per node (index = CalculiX id - 1), last increment
  std::vector<Vec3> reaction;      // per node, last increment; zero where RF was not printed
  double time = 0.0;               // step time of those results (1 at the end of our decks)
  double wall_seconds = 0.0;       // how long ccx ran
};

// Writes work_dir/job.inp (creating work_dir), runs `ccx -i job` in work_dir with
// OMP_NUM_THREADS=1, its output going to work_dir/ccx.log, and reads work_dir/job.dat.
// Not ok when ccx is missing, exits with a non-zero status, prints *ERROR, or leaves no
// displacements. The files stay in work_dir. The executable is $PHYMUL_CCX when set,
// otherwise ccx on PATH.
CalculixResult run_calculix(const std::string& deck, const std::filesystem::path& work_dir);

// Reads the *NODE PRINT tables of a .dat file: "displacements (vx,vy,vz) for set ... and
// time t" and "forces (fx,fy,fz) for set ... and time t", each followed by lines
// "id x y z". Keeps the last time printed (tables of several sets at that time are merged).
// Accepts Fortran exponents without the 'E' (1.234567-100). Not ok without displacements,
// with a node missing from them, or with a non-finite value.
CalculixResult parse_calculix_dat(const std::string& text);

// True when the CalculiX executable (see run_calculix) runs and reports its version.
// Checked once per process.
bool calculix_available();

}  // namespace phymul::fem

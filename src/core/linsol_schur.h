/* A SUNLinearSolver for IDA's iteration matrix J = dF/dy + cj dF/dy' of the minimal formulation
 * (include/flex3rpr/residual.h). Private.
 *
 * Its first nz rows are the kinematic rows z' - u, so with y = [z | r], r = [u | lag | W]:
 *   J = [ cj I   -E   ]      E = [I 0 ... 0] picks u out of r.
 *       [ J_rz   J_rr ]
 * The solve eliminates x_z = (b_z + x_u) / cj and factors only the Schur complement
 *   S = J_rr + J_rz E / cj          (ny - nz square: 13 against 25 for r = 3)
 * with partial pivoting; cj is read from J itself (J_00 = cj, exactly). The kinematic rows must
 * be exact, as the analytic Jacobian makes them: with difference quotients use the dense solver.
 *
 * A direct solver on IDA's dense SUNMatrix: IDA's Jacobian function still fills the whole J. */
#ifndef FLEX3RPR_LINSOL_SCHUR_H
#define FLEX3RPR_LINSOL_SCHUR_H

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#ifdef __cplusplus
extern "C" {
#endif

/* NULL when out of memory. nz: independent coordinates; ny: the state size (> 2 nz). */
SUNLinearSolver f3r_schur_linsol_create(SUNContext ctx, int nz, int ny);

#ifdef __cplusplus
}
#endif

#endif

/* A SUNLinearSolver for IDA's iteration matrix J = dF/dy + cj dF/dy' of the formulations whose
 * first nk rows are kinematic (residual.h). Private.
 *
 * With y = [k | r]:  J = [ J_kk  J_kr ]   where J_kk = cj I exactly (minimal: the rows z' - u)
 *                        [ J_rk  J_rr ]   or cj I + d(G^T mu)/dq (dae: q' - v + G^T mu).
 * The solve eliminates x_k = (b_k - J_kr x_r) / cj and factors only the Schur complement
 *   S = J_rr - J_rk J_kr / cj
 * (minimal r = 3: 13 x 13 instead of 25; dae: 31 instead of 49) with partial pivoting. J_kr is
 * sparse (-I on the rates, G^T on mu): only its nonzero entries are used (their pattern recorded
 * at setup). For dae the solver drops d(G^T mu)/dq from J_kk: mu vanishes along exact solutions
 * (it is roundoff-sized), so Newton converges to the same residual-zero state with an iteration
 * matrix that differs from the exact one by O(|mu|).
 * For minimal the elimination is exact. The kinematic rows must come from the analytic
 * Jacobian: with difference quotients use the dense solver.
 *
 * cj is read at each setup from *cj (the stepper's Jacobian function stores it there).
 * A direct solver on IDA's dense SUNMatrix: IDA's Jacobian function still fills the whole J. */
#ifndef FLEX3RPR_LINSOL_SCHUR_H
#define FLEX3RPR_LINSOL_SCHUR_H

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#ifdef __cplusplus
extern "C" {
#endif

/* NULL when out of memory. nk: kinematic rows (minimal: nz; dae: nq); ny: the state size. */
SUNLinearSolver f3r_schur_linsol_create(SUNContext ctx, int nk, int ny, const double* cj);

#ifdef __cplusplus
}
#endif

#endif

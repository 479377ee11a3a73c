/* Linearised natural frequencies of the constrained system (minimal coordinates
 * z = (X_p, Y_p, phi_p, eta)) about the scene's initial platform pose with zero deflection,
 * zero velocity and no forces: det(K - omega^2 B^T M B) = 0. The three rigid-body modes of the
 * platform have zero frequency (the mechanism is unactuated in this linearisation). */
#ifndef FLEX3RPR_MODAL_H
#define FLEX3RPR_MODAL_H

#include "flex3rpr/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* hz receives n_independent frequencies in ascending order (Hz); *count their number. */
f3r_status f3r_modal_frequencies(const f3r_model* model, double* hz, int* count, f3r_error* err);

#ifdef __cplusplus
}
#endif
#endif

/* The linear layer's shared parts (linear_model.c), for state_space.c and the accuracy layer
 * above: sampled inputs and responses, the mass matrix's factor. Private to the core. */
#ifndef FLEX3RPR_LINEAR_PARTS_H
#define FLEX3RPR_LINEAR_PARTS_H

#include "flex3rpr/linear.h"
#include "flex3rpr/sim.h"

/* The scene's inputs (through the actuator lag) at t_k = k dt, k < count, into u
 * (F3R_RIGID_FORCES a sample): what f3r_linear_response samples (linear_model.c). */
void f3r_linear_sample_inputs(const f3r_model* model, double dt, int count, double* u);

/* f3r_linear_response (other NULL) or f3r_linear_difference_response (order 1) on inputs sampled
 * by f3r_linear_sample_inputs at the same dt and count (inputs may be NULL: sampled here). */
f3r_status f3r_linear_response_sampled(const f3r_linear_model* lin, const f3r_model* model,
                                       const f3r_model* other, const double* inputs, double dt,
                                       int count, int order, double* pose, int* unreachable,
                                       f3r_error* err);

/* L = the Cholesky factor of the linear model's mass matrix (n x n, linear_model.c); who names
 * the caller in the error when the matrix is not positive definite. */
f3r_status f3r_linear_mass_factor(const f3r_linear_model* lin, double* L, const char* who,
                                  f3r_error* err);

#endif

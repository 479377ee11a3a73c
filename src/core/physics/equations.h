/* The equations of motion assembled from one forward pass (data.h): M and G and their products,
 * the energies, the constrained system [M -G^T; G 0] and its solve, the end stops' forces, and
 * the minimal formulation's accelerations and loop forces. Nothing here runs the forward pass:
 * each function reads the stages the comment names. Private. */
#ifndef FLEX3RPR_EQUATIONS_H
#define FLEX3RPR_EQUATIONS_H

#include <stddef.h>

#include "data.h"

/* --- M and G at the position and mass stages (matrices column-major, leading dimension ld;
 * f3r_*_add_* add scale times the matrix into A) -------------------------------------------- */
void f3r_data_mass_times(const f3r_model* m, const f3r_data* d, const double* x, double* out);
void f3r_data_add_mass_matrix(const f3r_model* m, const f3r_data* d, double scale, double* A,
                              int ld);
void f3r_data_constraint_times(const f3r_model* m, const f3r_data* d, const double* x, double* out);
void f3r_data_constraint_transpose_times(const f3r_model* m, const f3r_data* d, const double* y,
                                         double* out);
void f3r_data_add_constraint_jacobian(const f3r_model* m, const f3r_data* d, double scale,
                                      double* A, int ld);
void f3r_data_add_constraint_jacobian_transpose(const f3r_model* m, const f3r_data* d, double scale,
                                                double* A, int ld);

/* Link k's dependent block G_d = [e, L n - w e] of the constraint Jacobian (det L):
 *   (rho, theta) = G_d^{-1} (vx, vy):  theta = (n . V) / L,  rho = e . V + w theta
 * (its transpose: equations.c). */
static inline void f3r_link_solve_dependent(const f3r_link_data* k, double vx, double vy,
                                            double* rho, double* theta) {
  const double c = k->c, s = k->s, w = k->w, len = k->len; /* read before rho, theta are written */
  const double th = (-s * vx + c * vy) / len;
  *rho = (c * vx + s * vy) + w * th;
  *theta = th;
}

/* --- the energy stage (forward.c calls it last): T = v^T M v / 2 and V = sum k_j eta_j^2 / 2
 * from the position, mass and velocity stages ---------------------------------------------- */
void f3r_energy_stage(const f3r_model* m, f3r_data* d);

/* --- the constrained system at the position, mass, velocity and force stages ---------------- */
/* [M -G^T; G 0] [a; lambda] = [Q - h - k; -gamma] solved for the accelerations a (nq) and the
 * multipliers lambda (6). work holds f3r_solve_accelerations_work_size doubles.
 * F3R_ERR_SINGULAR if the system is singular. */
f3r_status f3r_data_solve_accelerations(const f3r_model* m, const f3r_data* d, const double* Q,
                                        double* a, double* lambda, double* work);
size_t f3r_solve_accelerations_work_size(const f3r_model* m);

/* --- end stops held as contact ---------------------------------------------------------------- */
/* A leg at rest against a stop is locked there: its stroke obeys the acceleration constraint
 * rho_i'' = -2 a rho_i' - a^2 (rho_i - stop) (a = F3R_STOP_BAUMGARTE_RATE, which pulls the
 * integrator's drift back onto the stop), and the stop's force f_i on rho_i is that constraint's
 * Lagrange multiplier. side[i]: -1 locked at stroke_min, +1 at stroke_max, 0 free. */
typedef struct f3r_stop_locks {
  int side[3];
} f3r_stop_locks;
#define F3R_STOP_BAUMGARTE_RATE 200.0
int f3r_stop_locks_any(const f3r_stop_locks* locks);
/* The stops' forces f (3, zero on free legs; N along rho_i) under the generalized forces Q
 * without them: [M -G^T -E; G 0 0; E^T 0 0] [a; lambda; f] = [Q - h - k; -gamma; -baumgarte],
 * E the unit columns of the locked legs. work holds f3r_stop_forces_work_size doubles. */
f3r_status f3r_data_stop_forces(const f3r_model* m, const f3r_data* d, const f3r_stop_locks* locks,
                                const double* Q, double* f, double* work);
size_t f3r_stop_forces_work_size(const f3r_model* m);
/* The same solve, with the accelerations a (nq) under those forces too when a is not NULL (with
 * no leg locked: the accelerations of the free system). */
f3r_status f3r_data_contact_solve(const f3r_model* m, const f3r_data* d,
                                  const f3r_stop_locks* locks, const double* Q, double* f,
                                  double* a, double* work);
/* The stops stage: with legs locked (d->locks), their forces at d into d->stop_force, added to
 * d->Q and to the power d->power; zero and d unchanged when no leg is locked. */
f3r_status f3r_stop_stage(const f3r_model* m, f3r_data* d);

/* --- the acceleration stages ---------------------------------------------------------------------- */
/* Open: at the given accelerations d->vdot and multipliers d->multipliers, the dynamic residual
 * d->R = M a + h + k - Q - G^T lambda (d->lambda the given ones; d->a is not filled) and, with
 * d->mu, G^T mu and G v. Closed (the minimal formulation): from the independent accelerations d->udot (NULL: zero),
 * the accelerations d->a (the dependent ones from the loop closure), R = M a + h + k - Q in d->R,
 * the loop forces d->lambda and, where d->reduced points, the reduced equations
 * B^T R = R_z - G_z^T lambda. */
void f3r_acceleration_stage(const f3r_model* m, f3r_data* d, int closed);

#endif

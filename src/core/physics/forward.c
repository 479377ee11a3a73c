/* The forward pass only sequences the stages, each of which lives in a file of its own and never
 * calls back:
 *   position   q                 -> per link c, s, L, w, modal sums; the platform joints'
 *                                   directions; G's blocks; g                      (position.c)
 *   (closed)   z                 -> the same, with rho_i and the legs' directions from the loop
 *                                   closure (the minimal formulation), q = q_closed (position.c)
 *   mass       the above         -> per link blocks of M                              (mass.c)
 *   velocity   v + the above     -> per link rates; h; gamma                      (velocity.c)
 *   (closed)   u + the above     -> rho_i', theta_i' from G v = 0, then as velocity, v = v_closed
 *   forces     t + the above     -> k, Q (held, effects, actuator lag), power       (forces.c,
 *                                                                                   effects.c)
 *   stops      locks + the above -> the locked legs' stop forces, into Q          (equations.c)
 *   acceleration   v', lambda    -> R = M a + h + k - Q - G^T lambda (the redundant formulations)
 *   (closed)   u'                -> a by the loop closure, R, lambda, B^T R (minimal)
 *   energy     the above         -> T, V                                         (equations.c)
 * What follows a pass reads its stages: the formulations' rows (form_dae.c, form_minimal.c), their
 * Jacobians, and the queries (queries.c). Each stage runs over the three links in turn: the legs'
 * square roots and divisions then run side by side (one pass per link measured slower,
 * f3r_microbench). */
#include "equations.h"
#include "forces.h"
#include "forward.h"
#include "mass.h"
#include "position.h"
#include "velocity.h"

f3r_status f3r_forward(const f3r_model* m, f3r_data* d, unsigned what) {
  const int closed_q = (what & F3R_FWD_POSITION_CLOSED) != 0;
  const int position = closed_q || (what & F3R_FWD_POSITION);
  const int closed_v = (what & F3R_FWD_VELOCITY_CLOSED) != 0;
  f3r_status st = F3R_OK;
  if (closed_q)
    st = f3r_position_stage_closed(m, d);
  else if (position)
    f3r_position_stage(m, d);
  if (st != F3R_OK) return st;
  if (position) f3r_mass_stage(m, d);
  if (closed_v || (what & F3R_FWD_VELOCITY)) f3r_velocity_stage(m, d, closed_v);
  if (what & F3R_FWD_FORCES) f3r_force_stage(m, d);
  if ((what & F3R_FWD_STOPS) && (st = f3r_stop_stage(m, d)) != F3R_OK) return st;
  if (what & F3R_FWD_ACCELERATION) f3r_acceleration_stage(m, d, 0);
  if (what & F3R_FWD_ACCELERATION_CLOSED) f3r_acceleration_stage(m, d, 1);
  if (what & F3R_FWD_ENERGY) f3r_energy_stage(m, d);
  return F3R_OK;
}

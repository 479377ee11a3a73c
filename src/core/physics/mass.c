/* The mass stage: each link's blocks of M(q), from its kinetic energy (eq. 9 with
 * w = sum eta_j psi_j(x/l), m = rho_A l, modes orthonormal):
 *   T_i = 1/2 I_c th'^2 + 1/2 m rho'^2 + 1/2 J th'^2 + th' sum c_j eta_j' + 1/2 m |eta'|^2
 *         [exact kinematics: - m rho' th' s + 1/2 m th'^2 |eta|^2]
 *   J = m (l^2/3 + l rho + rho^2),  c_j = m (l a_j + rho b_j),  s = sum b_j eta_j,
 *   a_j = int xi psi_j, b_j = int psi_j.
 * The exact terms come from the axial velocity rho' - w th' of a beam point, which the paper's
 * eq. (9) drops. The platform (eq. 10) adds diag(m_p, m_p, I_p), constant, so it has no block
 * here (equations.c adds it where M is used). */
#include "mass.h"

void f3r_mass_stage(const f3r_model* m, f3r_data* d) {
  const double l = m->link_length, mass = m->link_mass, e = m->exact_kinematics ? 1.0 : 0.0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    f3r_link_data* k = &d->link[i];
    const double rho = d->q[i];
    k->m_rho_theta = -e * mass * k->mean_defl;
    k->m_theta_theta =
        m->cylinder_inertia + mass * (l * l / 3.0 + l * rho + rho * rho) + e * mass * k->eta_sq;
    for (int j = 0; j < lp->modes; ++j)
      k->m_theta_eta[j] = mass * (l * lp->first_moment[j] + rho * lp->mean[j]);
  }
}

/* The workspace: one allocation per array, made once per model, none in the step loop. */
#include <stdlib.h>

#include "workspace.h"

f3r_workspace* f3r_workspace_create(const f3r_model* m) {
  f3r_workspace* ws = calloc(1, sizeof *ws);
  if (!ws) return NULL;
  ws->nq = m->nq;
  ws->nz = m->n_independent;
  const int ny_dae = f3r_state_size(m, F3R_FORMULATION_DAE); /* the largest */
  ws->ny = ny_dae;
  ws->solve_work = calloc(f3r_solve_accelerations_work_size(m), sizeof(double));
  ws->y_perturbed = calloc((size_t)ny_dae, sizeof(double));
  ws->dQ = calloc(2 * (size_t)m->nq * (size_t)m->nq, sizeof(double));
  ws->stop_work = calloc(f3r_stop_forces_work_size(m), sizeof(double));
  const size_t nq = (size_t)m->nq, nz = (size_t)ws->nz;
  ws->jac_work = calloc(2 * nq * nq + 18 * nq + 3 * nq * nz + 6 * nz, sizeof(double));
  if (!ws->solve_work || !ws->y_perturbed || !ws->dQ || !ws->jac_work || !ws->stop_work) {
    f3r_workspace_destroy(ws);
    return NULL;
  }
  return ws;
}

void f3r_workspace_destroy(f3r_workspace* ws) {
  if (!ws) return;
  free(ws->solve_work);
  free(ws->jac_work);
  free(ws->y_perturbed);
  free(ws->dQ);
  free(ws->stop_work);
  free(ws);
}

long f3r_workspace_sincos_pairs(const f3r_workspace* ws) { return ws->data.sincos_pairs; }

void f3r_workspace_set_locks(f3r_workspace* ws, const int side[3]) {
  for (int i = 0; i < 3; ++i) ws->locks.side[i] = side[i];
}

/* What the CLI reports about a model instead of running it: --geometry, --modal,
 * --linear-path and --linearise. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "flex3rpr/linear.h"
#include "flex3rpr/modal.h"
#include "flex3rpr/linear_export.h"
#include "model_reports.h"

/* The model's geometry, masses and stroke as JSON: the URDF generator (nodes/make_urdf.py)
 * takes them from here, so that the URDF and the node's model come from one scene. */
void f3r_cli_print_geometry(const f3r_model* model) {
  const f3r_scene* s = f3r_model_scene(model);
  const f3r_geometry g = f3r_model_geometry(model);
  printf("{\"base_joint\": [[%.17g, %.17g], [%.17g, %.17g], [%.17g, %.17g]],\n", g.base_joint[0][0],
         g.base_joint[0][1], g.base_joint[1][0], g.base_joint[1][1], g.base_joint[2][0],
         g.base_joint[2][1]);
  printf(" \"platform_angle\": [%.17g, %.17g, %.17g], \"platform_radius\": %.17g,\n",
         g.platform_angle[0], g.platform_angle[1], g.platform_angle[2], g.platform_radius);
  printf(" \"platform_mass\": %.17g, \"platform_inertia\": %.17g,\n", g.platform_mass,
         g.platform_inertia);
  printf(" \"link_length\": %.17g, \"link_diameter\": %.17g, \"link_mass\": %.17g,\n",
         g.link_length, s->link_diameter, g.link_mass);
  printf(
      " \"cylinder_length\": %.17g, \"cylinder_inner_diameter\": %.17g, "
      "\"cylinder_outer_diameter\": %.17g,"
      " \"cylinder_mass\": %.17g,\n",
      g.cylinder_length, s->cylinder_inner_diameter, s->cylinder_outer_diameter, g.cylinder_mass);
  printf(" \"stroke_min\": %.17g, \"stroke_max\": %.17g, \"end_stops\": %s,\n", g.stroke_min,
         g.stroke_max, g.end_stops ? "true" : "false");
  char basis[3][96];
  for (int i = 0; i < 3; ++i) f3r_model_link_basis_name(model, i, basis[i], sizeof basis[i]);
  printf(" \"link_basis\": [\"%s\", \"%s\", \"%s\"]}\n", basis[0], basis[1], basis[2]);
}

/* The frequencies as CSV (mode, hz, 17 digits) with each link's basis: for scripts. */
static int write_modal_csv(const f3r_model* m, const char* path, const double* hz, int count) {
  FILE* f = fopen(path, "w");
  if (!f) {
    fprintf(stderr, "flex3rpr_sim: cannot write %s\n", path);
    return 1;
  }
  fprintf(f, "mode,hz");
  for (int i = 0; i < 3; ++i) fprintf(f, ",link_%d_modes,link_%d_static_shapes", i + 1, i + 1);
  fprintf(f, "\n");
  for (int k = 0; k < count; ++k) {
    fprintf(f, "%d,%.17g", k + 1, hz[k]);
    for (int i = 0; i < 3; ++i) {
      const f3r_link_params* lp = f3r_model_link(m, i);
      fprintf(f, ",%d,%d", lp->modes - lp->static_shapes, lp->static_shapes);
    }
    fprintf(f, "\n");
  }
  fclose(f);
  return 0;
}

int f3r_cli_run_modal(const f3r_model* m, const char* csv_path) {
  double hz[F3R_MAX_Q];
  int count = 0;
  f3r_error err = {0};
  if (f3r_modal_frequencies(m, hz, &count, &err) != F3R_OK) {
    fprintf(stderr, "flex3rpr_sim: %s\n", err.message);
    return 1;
  }
  printf("# linearised natural frequencies of the constrained system at the initial pose (Hz)\n");
  for (int i = 0; i < 3; ++i) {
    char basis[96];
    printf("# links[%d]: %s\n", i, f3r_model_link_basis_name(m, i, basis, sizeof basis));
  }
  for (int k = 0; k < count; ++k) printf("%d %.6f\n", k + 1, hz[k]);
  return csv_path ? write_modal_csv(m, csv_path, hz, count) : 0;
}

/* The platform pose of the linearised model (linear.h) at the output step, as CSV: first order
 * and with the second-order correction. */
int f3r_cli_write_linear_path(const f3r_model* m, const char* path) {
  const double dt = f3r_model_scene(m)->output_step;
  const int count = (int)llround(f3r_model_scene(m)->duration / dt) + 1;
  double* pose = malloc((size_t)count * 6 * sizeof(double));
  f3r_linear_model* lin = NULL;
  f3r_error err = {0};
  FILE* f = NULL;
  int rc = 1, unreachable = 0;
  if (!pose)
    fprintf(stderr, "flex3rpr_sim: out of memory\n");
  else if (f3r_linearise(m, &lin, &err) != F3R_OK ||
           f3r_linear_response(lin, m, dt, count, 1, pose, NULL, &err) != F3R_OK ||
           f3r_linear_response(lin, m, dt, count, 2, pose + 3 * count, &unreachable, &err) !=
               F3R_OK)
    fprintf(stderr, "flex3rpr_sim: %s\n", err.message);
  else if (!(f = fopen(path, "w")))
    fprintf(stderr, "flex3rpr_sim: cannot write %s\n", path);
  else {
    fprintf(f, "t,x_p,y_p,phi_p,x_p_2,y_p_2,phi_p_2\n");
    for (int k = 0; k < count; ++k) {
      const double *a = pose + 3 * k, *b = pose + 3 * (count + k);
      fprintf(f, "%.10g,%.15g,%.15g,%.15g,%.15g,%.15g,%.15g\n", k * dt, a[0], a[1], a[2], b[0],
              b[1], b[2]);
    }
    fclose(f);
    if (unreachable)
      printf("linear path: %d samples beyond the reachable poses (no correction there)\n",
             unreachable);
    rc = 0;
  }
  f3r_linear_destroy(lin);
  free(pose);
  return rc;
}

/* The state-space form of the linearisation about the scene's initial pose (linear.h) as a
 * MATLAB level-4 .mat file at path and JSON beside it (linear_export.h). */
int f3r_cli_write_state_space(const f3r_model* m, const char* path) {
  f3r_state_space* ss = NULL;
  f3r_error err = {0};
  char json[4096], why[1024];
  if (f3r_linear_json_path(path, json, sizeof json) != 0) {
    fprintf(stderr, "flex3rpr_sim: --linearise: path too long: %s\n", path);
    return 1;
  }
  if (f3r_state_space_create(m, &ss, &err) != F3R_OK) {
    fprintf(stderr, "flex3rpr_sim: %s\n", err.message);
    return 1;
  }
  int rc = 0;
  if (f3r_linear_write_mat(ss, path, why, sizeof why) != 0 ||
      f3r_linear_write_json(ss, json, why, sizeof why) != 0) {
    fprintf(stderr, "flex3rpr_sim: --linearise: %s\n", why);
    rc = 1;
  } else {
    printf(
        "linearised at pose (%.9g, %.9g, %.9g): wrote %s (MATLAB level 4) and %s: nx %d, nu %d, "
        "ny %d\n",
        ss->x0[0], ss->x0[1], ss->x0[2], path, json, ss->nx, ss->nu, ss->ny);
  }
  f3r_state_space_destroy(ss);
  return rc;
}

/* --check and --geometry: the model only, before the accuracy knob's report. */
int f3r_cli_describe_model(FILE* human, const cli_options* o, const f3r_model* model) {
  if (o->check) /* the scene, its overrides and the model are valid: what a sweep checks first */
    fprintf(human, "ok: %s, nq %d\n", o->scene_path, f3r_model_nq(model));
  else
    f3r_cli_print_geometry(model);
  return 0;
}

/* The analyses that replace a simulation (--linear-path, --linearise, --modal): the exit code,
 * or -1 when none was asked for. */
int f3r_cli_analyse(const cli_options* o, const f3r_model* model) {
  if (o->linear_path) return f3r_cli_write_linear_path(model, o->linear_path);
  if (o->linearise_path) return f3r_cli_write_state_space(model, o->linearise_path);
  if (o->modal || o->modal_csv) return f3r_cli_run_modal(model, o->modal_csv);
  return -1;
}

/* Error reporting of the flex3rpr core: every fallible call returns an f3r_status and, where an
 * f3r_error is passed, a message saying what was wrong. The core never prints or exits. */
#ifndef FLEX3RPR_STATUS_H
#define FLEX3RPR_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  F3R_OK = 0,
  F3R_ERR_ARGUMENT = 1, /* a bad argument from the caller (NULL, wrong size, NaN) */
  F3R_ERR_SCENE = 2,    /* a scene value outside its allowed range, or a bad scene file */
  F3R_ERR_MEMORY = 3,   /* allocation failed (only at creation, never while stepping) */
  F3R_ERR_SOLVER = 4,   /* SUNDIALS reported a failure it could not recover from */
  F3R_ERR_SINGULAR = 5, /* a configuration where the model degenerates (rho_i + l -> 0) */
  F3R_ERR_NONFINITE = 6 /* a NaN or Inf reached the state; the last good state is kept */
} f3r_status;

typedef struct {
  f3r_status code;
  char message[512];
  /* For F3R_ERR_SCENE from f3r_scene_validate: the scene field at fault, as the YAML path
   * ("solver.rtol", "inputs.rho_3.table.time[2]"), so that a loader can point at its line
   * without parsing the message; empty otherwise. */
  char field[128];
} f3r_error;

/* A short, static name for a status, e.g. "F3R_ERR_SCENE". */
const char* f3r_status_name(f3r_status status);

/* Fills err (if not NULL) with code and a printf-style message, and clears err->field;
 * returns code. */
f3r_status f3r_error_set(f3r_error* err, f3r_status code, const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* F3R_ERR_SCENE about one scene field: err->field = field, err->message = "field: what".
 * message_field, when not NULL, replaces field in the message (a list item is located by its
 * own path, "x[2]", while the message names the list, "x"). Returns F3R_ERR_SCENE. */
f3r_status f3r_scene_error(f3r_error* err, const char* field, const char* message_field,
                           const char* format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#ifdef __cplusplus
}
#endif
#endif

#include "flex3rpr/status.h"

#include <stdarg.h>
#include <stdio.h>

const char* f3r_status_name(f3r_status status) {
  switch (status) {
    case F3R_OK: return "F3R_OK";
    case F3R_ERR_ARGUMENT: return "F3R_ERR_ARGUMENT";
    case F3R_ERR_SCENE: return "F3R_ERR_SCENE";
    case F3R_ERR_MEMORY: return "F3R_ERR_MEMORY";
    case F3R_ERR_SOLVER: return "F3R_ERR_SOLVER";
    case F3R_ERR_SINGULAR: return "F3R_ERR_SINGULAR";
    case F3R_ERR_NONFINITE: return "F3R_ERR_NONFINITE";
  }
  return "F3R_ERR_UNKNOWN";
}

f3r_status f3r_error_set(f3r_error* err, f3r_status code, const char* format, ...) {
  if (err) {
    err->code = code;
    va_list args;
    va_start(args, format);
    vsnprintf(err->message, sizeof err->message, format, args);
    va_end(args);
    err->field[0] = '\0';
  }
  return code;
}

f3r_status f3r_scene_error(f3r_error* err, const char* field, const char* message_field,
                           const char* format, ...) {
  if (err) {
    char what[sizeof err->message];
    va_list args;
    va_start(args, format);
    vsnprintf(what, sizeof what, format, args);
    va_end(args);
    err->code = F3R_ERR_SCENE;
    snprintf(err->message, sizeof err->message, "%s: %s", message_field ? message_field : field,
             what);
    snprintf(err->field, sizeof err->field, "%s", field);
  }
  return F3R_ERR_SCENE;
}

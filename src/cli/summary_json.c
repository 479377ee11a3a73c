/* The JSON writer of summary_json.h. */
#include "summary_json.h"

#include <math.h>

/* A string's characters, escaped as JSON requires (quotes, backslashes, control characters). */
static void write_escaped(FILE* f, const char* s) {
  fputc('"', f);
  for (const unsigned char* c = (const unsigned char*)s; *c; ++c) {
    if (*c == '"' || *c == '\\')
      fprintf(f, "\\%c", *c);
    else if (*c == '\n')
      fputs("\\n", f);
    else if (*c == '\t')
      fputs("\\t", f);
    else if (*c == '\r')
      fputs("\\r", f);
    else if (*c < 0x20)
      fprintf(f, "\\u%04x", *c);
    else
      fputc(*c, f);
  }
  fputc('"', f);
}

/* The separator, the indentation and the key of the next member. */
static void member(f3r_json* j, const char* key) {
  fputs(j->count[j->depth]++ ? ",\n" : "\n", j->f);
  for (int k = 0; k <= j->depth; ++k) fputs("  ", j->f);
  if (key) {
    write_escaped(j->f, key);
    fputs(": ", j->f);
  }
}

static void open_level(f3r_json* j, const char* key, char bracket) {
  member(j, key);
  fputc(bracket, j->f);
  if (j->depth + 1 < F3R_JSON_MAX_DEPTH) {
    j->count[++j->depth] = 0;
    j->closer[j->depth] = bracket == '{' ? '}' : ']';
  }
}

void f3r_json_begin(f3r_json* j, FILE* f) {
  j->f = f;
  j->depth = 0;
  j->count[0] = 0;
  fputc('{', f);
}

void f3r_json_end(f3r_json* j) { fputs("\n}\n", j->f); }

void f3r_json_object(f3r_json* j, const char* key) { open_level(j, key, '{'); }

void f3r_json_array(f3r_json* j, const char* key) { open_level(j, key, '['); }

void f3r_json_close(f3r_json* j) {
  if (j->depth == 0) return;
  if (j->count[j->depth]) {
    fputc('\n', j->f);
    for (int k = 0; k < j->depth; ++k) fputs("  ", j->f);
  }
  fputc(j->closer[j->depth--], j->f);
}

void f3r_json_number(f3r_json* j, const char* key, double value) {
  member(j, key);
  if (isfinite(value))
    fprintf(j->f, "%.17g", value);
  else
    fputs("null", j->f);
}

void f3r_json_integer(f3r_json* j, const char* key, long value) {
  member(j, key);
  fprintf(j->f, "%ld", value);
}

void f3r_json_bool(f3r_json* j, const char* key, int value) {
  member(j, key);
  fputs(value ? "true" : "false", j->f);
}

void f3r_json_string(f3r_json* j, const char* key, const char* value) {
  member(j, key);
  if (value)
    write_escaped(j->f, value);
  else
    fputs("null", j->f);
}

void f3r_json_null(f3r_json* j, const char* key) {
  member(j, key);
  fputs("null", j->f);
}

/* A small JSON writer for the CLI's machine-readable summary (--summary-json): objects, arrays,
 * numbers (%.17g, which round-trip; null when not finite), whole numbers, booleans and escaped
 * strings, indented two spaces a level. */
#ifndef FLEX3RPR_SUMMARY_JSON_H
#define FLEX3RPR_SUMMARY_JSON_H

#include <stdio.h>

#define F3R_JSON_MAX_DEPTH 8

typedef struct {
  FILE* f;
  int depth;
  int count[F3R_JSON_MAX_DEPTH];   /* members written so far at each level */
  char closer[F3R_JSON_MAX_DEPTH]; /* '}' or ']' of each level */
} f3r_json;

/* key is the member's name inside an object, NULL inside an array. */
void f3r_json_begin(f3r_json* j, FILE* f); /* the outer object */
void f3r_json_end(f3r_json* j);            /* closes it, with a newline */
void f3r_json_object(f3r_json* j, const char* key);
void f3r_json_array(f3r_json* j, const char* key);
void f3r_json_close(f3r_json* j); /* the innermost object or array */
void f3r_json_number(f3r_json* j, const char* key, double value);
void f3r_json_integer(f3r_json* j, const char* key, long value);
void f3r_json_bool(f3r_json* j, const char* key, int value);
void f3r_json_string(f3r_json* j, const char* key, const char* value); /* NULL: null */
void f3r_json_null(f3r_json* j, const char* key);

#endif

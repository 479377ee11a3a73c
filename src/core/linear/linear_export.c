/* MATLAB level-4 and JSON export of a state-space model (linear_export.h). The bytes are
 * composed explicitly little-endian, whatever the host. */
#include "flex3rpr/linear_export.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void put_u32(unsigned char* b, uint32_t v) {
  for (int k = 0; k < 4; ++k) b[k] = (unsigned char)(v >> (8 * k));
}

static int write_header(FILE* f, int text, int rows, int cols, const char* name) {
  unsigned char h[20];
  const size_t namlen = strlen(name) + 1;
  put_u32(h, text ? 1u : 0u); /* MOPT: M = 0 little-endian, O = 0, P = 0 double, T */
  put_u32(h + 4, (uint32_t)rows);
  put_u32(h + 8, (uint32_t)cols);
  put_u32(h + 12, 0u); /* imagf */
  put_u32(h + 16, (uint32_t)namlen);
  return fwrite(h, 1, sizeof h, f) == sizeof h && fwrite(name, 1, namlen, f) == namlen;
}

static int write_double(FILE* f, double x) {
  uint64_t bits;
  unsigned char b[8];
  memcpy(&bits, &x, sizeof bits);
  for (int k = 0; k < 8; ++k) b[k] = (unsigned char)(bits >> (8 * k));
  return fwrite(b, 1, sizeof b, f) == sizeof b;
}

/* A rows x cols column-major matrix. */
static int write_matrix(FILE* f, const char* name, const double* a, int rows, int cols) {
  if (!write_header(f, 0, rows, cols, name)) return 0;
  for (long k = 0; k < (long)rows * cols; ++k)
    if (!write_double(f, a[k])) return 0;
  return 1;
}

/* count names of stride F3R_SS_NAME as a text matrix, blank-padded. */
static int write_names(FILE* f, const char* name, const char (*names)[F3R_SS_NAME], int count) {
  int width = 0;
  for (int r = 0; r < count; ++r) {
    const int len = (int)strlen(names[r]);
    if (len > width) width = len;
  }
  if (!write_header(f, 1, count, width, name)) return 0;
  for (int c = 0; c < width; ++c)
    for (int r = 0; r < count; ++r) {
      const int len = (int)strlen(names[r]);
      if (!write_double(f, c < len ? (double)(unsigned char)names[r][c] : (double)' ')) return 0;
    }
  return 1;
}

static int failed(const char* path, const char* doing, int saved_errno, char* why, size_t size) {
  snprintf(why, size, "cannot %s %s: %s", doing, path,
           saved_errno ? strerror(saved_errno) : "write error");
  return -1;
}

/* Closes f; -1 with why when the writes or the close failed. */
static int finish(FILE* f, int ok, const char* path, char* why, size_t size) {
  const int write_errno = ok ? 0 : errno;
  errno = 0;
  const int closed = fclose(f) == 0;
  if (!ok) return failed(path, "write", write_errno, why, size);
  if (!closed) return failed(path, "write", errno, why, size);
  return 0;
}

int f3r_linear_write_mat(const f3r_state_space* ss, const char* path, char* why, size_t why_size) {
  FILE* f = fopen(path, "wb");
  if (!f) return failed(path, "create", errno, why, why_size);
  const int ok =
      write_matrix(f, "A", ss->A, ss->nx, ss->nx) && write_matrix(f, "B", ss->B, ss->nx, ss->nu) &&
      write_matrix(f, "C", ss->C, ss->ny, ss->nx) && write_matrix(f, "D", ss->D, ss->ny, ss->nu) &&
      write_matrix(f, "x0", ss->x0, ss->nx, 1) && write_matrix(f, "y0", ss->y0, ss->ny, 1) &&
      write_names(f, "state_names", (const char(*)[F3R_SS_NAME])ss->state_names, ss->nx) &&
      write_names(f, "input_names", ss->input_names, ss->nu) &&
      write_names(f, "output_names", ss->output_names, ss->ny);
  return finish(f, ok, path, why, why_size);
}

/* x with the fewest digits (15..17) that read back as x: 0.01, not 0.010000000000000000208. */
static void json_number(FILE* f, const char* before, double x) {
  char text[32];
  for (int digits = 15; digits <= 17; ++digits) {
    snprintf(text, sizeof text, "%.*g", digits, x);
    if (strtod(text, NULL) == x) break;
  }
  fprintf(f, "%s%s", before, text);
}

static void json_rows(FILE* f, const char* name, const double* a, int rows, int cols) {
  fprintf(f, "  \"%s\": [", name);
  for (int r = 0; r < rows; ++r) {
    fprintf(f, "%s\n    [", r ? "," : "");
    for (int c = 0; c < cols; ++c) json_number(f, c ? ", " : "", a[(long)c * rows + r]);
    fprintf(f, "]");
  }
  fprintf(f, "\n  ],\n");
}

static void json_list(FILE* f, const char* name, const double* a, int count) {
  fprintf(f, "  \"%s\": [", name);
  for (int k = 0; k < count; ++k) json_number(f, k ? ", " : "", a[k]);
  fprintf(f, "],\n");
}

/* Names are [a-z0-9_] (state_space.c): no JSON escapes needed. */
static void json_names(FILE* f, const char* name, const char (*names)[F3R_SS_NAME], int count,
                       int last) {
  fprintf(f, "  \"%s\": [", name);
  for (int k = 0; k < count; ++k) fprintf(f, "%s\"%s\"", k ? ", " : "", names[k]);
  fprintf(f, "]%s\n", last ? "" : ",");
}

int f3r_linear_write_json(const f3r_state_space* ss, const char* path, char* why, size_t why_size) {
  FILE* f = fopen(path, "w");
  if (!f) return failed(path, "create", errno, why, why_size);
  fprintf(f, "{\n  \"nx\": %d,\n  \"nu\": %d,\n  \"ny\": %d,\n", ss->nx, ss->nu, ss->ny);
  json_rows(f, "A", ss->A, ss->nx, ss->nx);
  json_rows(f, "B", ss->B, ss->nx, ss->nu);
  json_rows(f, "C", ss->C, ss->ny, ss->nx);
  json_rows(f, "D", ss->D, ss->ny, ss->nu);
  json_list(f, "x0", ss->x0, ss->nx);
  json_list(f, "y0", ss->y0, ss->ny);
  json_names(f, "state_names", (const char(*)[F3R_SS_NAME])ss->state_names, ss->nx, 0);
  json_names(f, "input_names", ss->input_names, ss->nu, 0);
  json_names(f, "output_names", ss->output_names, ss->ny, 1);
  fprintf(f, "}\n");
  return finish(f, !ferror(f), path, why, why_size);
}

int f3r_linear_json_path(const char* mat_path, char* out, size_t size) {
  size_t stem = strlen(mat_path);
  if (stem >= 4 && !strcmp(mat_path + stem - 4, ".mat")) stem -= 4;
  if (stem + 6 > size) return -1;
  memcpy(out, mat_path, stem);
  memcpy(out + stem, ".json", 6);
  return 0;
}

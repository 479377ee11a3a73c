/* The export of a state-space model (flex3rpr/linear.h): `flex3rpr_sim SCENE --linearise
 * FILE.mat` writes a MATLAB level-4 .mat file and a JSON file beside it. Level 4 is what
 * Octave's and MATLAB's `load` and scipy.io.loadmat read without any library here.
 *
 * .mat layout: one record per variable, in this order: A (nx x nx), B (nx x nu), C (ny x nx),
 * D (ny x nu), x0 (nx x 1), y0 (ny x 1), state_names (nx rows), input_names (nu rows),
 * output_names (ny rows). A record is five little-endian int32 (type: 0 numeric, 1 text; mrows;
 * ncols; imagf = 0; namlen, the name's length with its NUL), the name and its NUL, then
 * mrows x ncols little-endian doubles, column-major. A text matrix has one name per row, padded
 * with blanks to the longest, its characters stored as their codes in doubles.
 *
 * JSON: {"nx", "nu", "ny", "A", "B", "C", "D" (lists of rows), "x0", "y0" (lists),
 * "state_names", "input_names", "output_names" (lists of strings)}, each number with the
 * fewest digits (15 to 17) that read back as the same double. */
#ifndef FLEX3RPR_LINEAR_EXPORT_H
#define FLEX3RPR_LINEAR_EXPORT_H

#include <stddef.h>

#include "flex3rpr/linear.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Each returns 0, or -1 with a message naming the path and the reason in why (why_size chars). */
int f3r_linear_write_mat(const f3r_state_space* ss, const char* path, char* why, size_t why_size);
int f3r_linear_write_json(const f3r_state_space* ss, const char* path, char* why, size_t why_size);

/* The JSON file's path for a .mat path: its ".mat" ending replaced by ".json", or ".json"
 * appended when it has none. Returns 0, or -1 when out (size chars) is too small. */
int f3r_linear_json_path(const char* mat_path, char* out, size_t size);

#ifdef __cplusplus
}
#endif
#endif

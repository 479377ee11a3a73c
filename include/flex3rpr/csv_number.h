/* The CSV's numbers: the text printf's "%.*g" writes (C locale), without its multiple-precision
 * path, which was two thirds of a knob run's CPU time on fixed-free links (csv_number.c). */
#ifndef FLEX3RPR_CSV_NUMBER_H
#define FLEX3RPR_CSV_NUMBER_H

/* Longest text f3r_format_g writes, its terminating zero included. */
#define F3R_FORMAT_G_SIZE 32

#ifdef __cplusplus
extern "C" {
#endif

/* Writes x into buf (F3R_FORMAT_G_SIZE bytes) as snprintf(buf, size, "%.*g", precision, x) would
 * in the C locale, the same bytes, and returns its length. */
int f3r_format_g(char* buf, double x, int precision);

#ifdef __cplusplus
}
#endif

#endif

/*
 * util/numparse.h — a fast, locale-independent decimal number parser for the text importers.
 *
 * Accepts [+-]digits[.digits][(e|E)[+-]digits] and the forms ".5", "5.". Results are correctly
 * rounded when the significand has at most 15 significant digits and the decimal exponent is
 * within ±22 (every number in typical BVH/CSV files); otherwise they are within one unit in the
 * last place of double precision. "inf", "nan" and hexadecimal floats are not numbers here.
 */
#ifndef AFFECT_NUMPARSE_H
#define AFFECT_NUMPARSE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Parses a number starting at p (no leading white space) and not beyond end. Returns the
 * pointer after the number, or NULL when p does not start with a number or the value overflows
 * to infinity. */
const char *affect_parse_double(const char *p, const char *end, double *out);

#ifdef __cplusplus
}
#endif
#endif

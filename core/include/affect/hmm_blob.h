/*
 * affect/hmm_blob.h — the model BLOB: a trained HMM (affect/hmm.h) together with its
 * observation definition (affect/features.h) and training report, versioned and checksummed
 * (docs/FORMATS.md).
 *
 * Usage:
 *     const affect_hmm *h = ...;  const affect_features *f = ...;   // a model, its features
 *     affect_error err;
 *     unsigned char *blob = NULL;  size_t size = 0;
 *     affect_hmm *h2 = NULL;
 *     affect_features *f2 = NULL;
 *     if (affect_hmm_blob_encode(h, f, &blob, &size, &err) != AFFECT_OK ||
 *         affect_hmm_blob_decode(blob, size, &h2, &f2, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_free(blob);
 *     affect_hmm_free(h2);
 *     affect_features_free(f2);
 *
 * Layout, version 1 (little-endian, written byte by byte):
 *    0  4  magic "AFHM"
 *    4  2  format version (1)
 *    6  2  flags (0; reserved)
 *    8  4  states N (1 .. 256)
 *   12  4  mixtures M (1 .. 64)
 *   16  4  dimension m (1 .. 4096)
 *   20  1  covariance (0 full, 1 diagonal)
 *   21  1  topology (0 ergodic, 1 left-to-right)
 *   22  1  start (0 first state, 1 learned)
 *   23  1  converged (0 or 1)
 *   24  4  max_jump
 *   28  4  max_iter
 *   32  8  tol (float64)
 *   40  8  reg (float64)
 *   48  8  seed (uint64)
 *   56  4  iterations I (≤ max_iter)
 *   60  4  reseeded
 *   64  4  training sequences
 *   68  4  length F of the feature definition
 *   72  8  training frames (uint64)
 *   80  F  feature definition (affect/features.h)
 *       (I + 1) × float64  total log-likelihood after initialisation and each iteration
 *       N × float64        start probabilities π
 *       N × N × float64    transitions A
 *       N × M × float64    mixture weights
 *       N × M × m × float64  means
 *       N × M × m × m (full) or N × M × m (diagonal) × float64  covariances
 *    8  FNV-1a 64-bit hash of every byte before it
 *
 * The decoder checks, in order: length ≥ header, magic, version, flags, sizes (overflow-checked),
 * the exact total length, the checksum, then the contents: the configuration
 * (affect_hmm_config_check), the feature definition and its dimension, finite values, and the
 * parameters themselves (affect_hmm_from_params: stochastic rows, positive-definite
 * covariances).
 */
#ifndef AFFECT_HMM_BLOB_H
#define AFFECT_HMM_BLOB_H

#include "affect/features.h"
#include "affect/hmm.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_HMM_MAGIC "AFHM"
#define AFFECT_HMM_BLOB_VERSION 1u
#define AFFECT_HMM_BLOB_HEADER_SIZE 80u

/* Encodes model h and its definition f into a new buffer of *size bytes (free with
 * affect_free). f's dimension must be h's. */
affect_status affect_hmm_blob_encode(const affect_hmm *h, const affect_features *f,
                                     unsigned char **out, size_t *size, affect_error *err);

/* Decodes and checks a model BLOB; never reads outside [data, data + size). Errors
 * (AFFECT_ERR_FORMAT unless said): "truncated: 12 bytes is shorter than the 80-byte header",
 * "not a model (bad magic bytes at offset 0)", "unknown format version 2 (this build reads
 * 1 .. 1)", "truncated: 950 bytes, expected 958 for 3 states x 1 mixtures x 6 dimensions",
 * "model checksum mismatch: the BLOB is corrupt", "non-finite value in the transitions
 * (offset 344)"; AFFECT_ERR_NOMEM. */
affect_status affect_hmm_blob_decode(const unsigned char *data, size_t size, affect_hmm **h,
                                     affect_features **f, affect_error *err);

/* FNV-1a 64-bit hash (the checksum of the BLOB). */
uint64_t affect_fnv1a64(const unsigned char *data, size_t size);

/* The same hash continued over more bytes: affect_fnv1a64(ab) =
 * affect_fnv1a64_update(affect_fnv1a64(a), b). */
uint64_t affect_fnv1a64_update(uint64_t h, const unsigned char *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif

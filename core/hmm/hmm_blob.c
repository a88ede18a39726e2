/*
 * hmm_blob.c — the model BLOB: encode a trained HMM with its feature definition and training
 * report; decode and check one (layout in affect/hmm_blob.h and docs/FORMATS.md).
 *
 * How it works: the encoder writes every field byte by byte, little-endian, and ends with the
 * FNV-1a 64-bit hash of everything before it. The decoder checks the fixed header and the sizes
 * it announces before touching the payload (every size product is overflow-checked), then the
 * exact length, then the hash — so a damaged BLOB is refused before any of its values is
 * trusted — then the contents, and finally rebuilds the model through affect_hmm_from_params
 * and affect_hmm_set_report. encode(decode(x)) gives back x byte for byte.
 */
#include "affect/hmm_blob.h"

#include "util/bytes.h"

#include <math.h>
#include <string.h>

uint64_t affect_fnv1a64_update(uint64_t h, const unsigned char *data, size_t size)
{
    for (size_t i = 0; i < size; i++)
        h = (h ^ data[i]) * 0x100000001b3ull;
    return h;
}

uint64_t affect_fnv1a64(const unsigned char *data, size_t size)
{
    return affect_fnv1a64_update(0xcbf29ce484222325ull, data, size);
}

/* Counts of doubles in each parameter section. */
typedef struct sections {
    size_t start, trans, weights, means, covs, total;
} sections;

/* The section sizes of an N × M × m model; false on overflow. */
static bool section_sizes(uint32_t n, uint32_t m_mix, uint32_t dim, bool full, sections *s)
{
    size_t nm, nmd, cov;
    s->start = n;
    s->trans = (size_t)n * n;
    if (!affect_mul_size(n, m_mix, &nm) || !affect_mul_size(nm, dim, &nmd))
        return false;
    s->weights = nm;
    s->means = nmd;
    if (full) {
        if (!affect_mul_size(nmd, dim, &cov))
            return false;
    } else {
        cov = nmd;
    }
    s->covs = cov;
    return affect_add_size(s->start, s->trans, &s->total) &&
           affect_add_size(s->total, s->weights, &s->total) &&
           affect_add_size(s->total, s->means, &s->total) &&
           affect_add_size(s->total, s->covs, &s->total);
}

/* Total BLOB size for a feature definition of f_len bytes and n_ll log-likelihoods. */
static bool blob_size(size_t f_len, size_t n_ll, const sections *s, size_t *size)
{
    size_t doubles, bytes;
    return affect_add_size(n_ll, s->total, &doubles) && affect_mul_size(doubles, 8, &bytes) &&
           affect_add_size(bytes, AFFECT_HMM_BLOB_HEADER_SIZE + 8, &bytes) &&
           affect_add_size(bytes, f_len, size);
}

static unsigned char *put_doubles(unsigned char *p, const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++, p += 8)
        affect_put_f64(p, v[i]);
    return p;
}

affect_status affect_hmm_blob_encode(const affect_hmm *h, const affect_features *f,
                                     unsigned char **out, size_t *size, affect_error *err)
{
    const affect_hmm_config *cfg = affect_hmm_get_config(h);
    if (affect_features_dim(f) != cfg->dim)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the feature definition has %u dimensions, the model %u",
                           affect_features_dim(f), cfg->dim);
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    sections s;
    size_t f_len, total;
    if (!section_sizes(cfg->n_states, cfg->n_mix, cfg->dim, cfg->cov == AFFECT_HMM_FULL, &s) ||
        !affect_features_encoded_size(f, &f_len) || f_len > UINT32_MAX ||
        !blob_size(f_len, (size_t)rep.iterations + 1, &s, &total))
        return affect_fail(err, AFFECT_ERR_RANGE, "model too large to encode");
    unsigned char *buf = affect_malloc(total);
    if (!buf)
        return affect_nomem(err);
    unsigned char *p = buf;
    memcpy(p, AFFECT_HMM_MAGIC, 4);
    affect_put_u16(p + 4, AFFECT_HMM_BLOB_VERSION);
    affect_put_u16(p + 6, 0);
    affect_put_u32(p + 8, cfg->n_states);
    affect_put_u32(p + 12, cfg->n_mix);
    affect_put_u32(p + 16, cfg->dim);
    p[20] = (unsigned char)cfg->cov;
    p[21] = (unsigned char)cfg->topology;
    p[22] = cfg->learn_start ? 1 : 0;
    p[23] = rep.converged ? 1 : 0;
    affect_put_u32(p + 24, cfg->max_jump);
    affect_put_u32(p + 28, cfg->max_iter);
    affect_put_f64(p + 32, cfg->tol);
    affect_put_f64(p + 40, cfg->reg);
    affect_put_u64(p + 48, cfg->seed);
    affect_put_u32(p + 56, rep.iterations);
    affect_put_u32(p + 60, rep.reseeded);
    affect_put_u32(p + 64, rep.n_sequences);
    affect_put_u32(p + 68, (uint32_t)f_len);
    affect_put_u64(p + 72, rep.n_frames);
    p += AFFECT_HMM_BLOB_HEADER_SIZE;
    affect_features_encode_into(f, p);
    p += f_len;
    p = put_doubles(p, rep.loglik, (size_t)rep.iterations + 1);
    p = put_doubles(p, affect_hmm_start(h), s.start);
    p = put_doubles(p, affect_hmm_transitions(h), s.trans);
    p = put_doubles(p, affect_hmm_weights(h), s.weights);
    p = put_doubles(p, affect_hmm_means(h), s.means);
    p = put_doubles(p, affect_hmm_covariances(h), s.covs);
    affect_put_u64(p, affect_fnv1a64(buf, (size_t)(p - buf)));
    *out = buf;
    *size = total;
    return AFFECT_OK;
}

/* Reads n doubles at *off into v, refusing non-finite ones (named by section and offset). */
static affect_status get_doubles(const unsigned char *data, size_t *off, double *v, size_t n,
                                 const char *section, affect_error *err)
{
    for (size_t i = 0; i < n; i++, *off += 8) {
        v[i] = affect_get_f64(data + *off);
        if (!isfinite(v[i]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in the %s (offset %zu)",
                               section, *off);
    }
    return AFFECT_OK;
}

affect_status affect_hmm_blob_decode(const unsigned char *data, size_t size, affect_hmm **h,
                                     affect_features **f, affect_error *err)
{
    if (size < AFFECT_HMM_BLOB_HEADER_SIZE)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the %u-byte header", size,
                           AFFECT_HMM_BLOB_HEADER_SIZE);
    if (affect_check_magic(data, AFFECT_HMM_MAGIC, NULL, "a model", 0, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    uint16_t version = affect_get_u16(data + 4);
    if (affect_check_version(version, AFFECT_HMM_BLOB_VERSION, NULL, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    uint16_t flags = affect_get_u16(data + 6);
    if (flags != 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "unknown flags 0x%04x (offset 6)", flags);

    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    cfg.n_states = affect_get_u32(data + 8);
    cfg.n_mix = affect_get_u32(data + 12);
    cfg.dim = affect_get_u32(data + 16);
    if (cfg.n_states < 1 || cfg.n_states > AFFECT_HMM_MAX_STATES)
        return affect_fail(err, AFFECT_ERR_FORMAT, "state count %u out of range (1 .. %u)",
                           cfg.n_states, AFFECT_HMM_MAX_STATES);
    if (cfg.n_mix < 1 || cfg.n_mix > AFFECT_HMM_MAX_MIX)
        return affect_fail(err, AFFECT_ERR_FORMAT, "mixture count %u out of range (1 .. %u)",
                           cfg.n_mix, AFFECT_HMM_MAX_MIX);
    if (cfg.dim < 1 || cfg.dim > AFFECT_HMM_MAX_DIM)
        return affect_fail(err, AFFECT_ERR_FORMAT, "dimension %u out of range (1 .. %u)", cfg.dim,
                           AFFECT_HMM_MAX_DIM);
    for (int i = 20; i < 24; i++)
        if (data[i] > 1)
            return affect_fail(err, AFFECT_ERR_FORMAT, "byte %d must be 0 or 1, got %u", i,
                               data[i]);
    cfg.cov = data[20] ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL;
    cfg.topology = data[21] ? AFFECT_HMM_LEFT_RIGHT : AFFECT_HMM_ERGODIC;
    cfg.learn_start = data[22] != 0;
    cfg.max_jump = affect_get_u32(data + 24);
    cfg.max_iter = affect_get_u32(data + 28);
    cfg.tol = affect_get_f64(data + 32);
    cfg.reg = affect_get_f64(data + 40);
    cfg.seed = affect_get_u64(data + 48);
    affect_hmm_report rep;
    memset(&rep, 0, sizeof rep);
    rep.converged = data[23] != 0;
    rep.iterations = affect_get_u32(data + 56);
    rep.reseeded = affect_get_u32(data + 60);
    rep.n_sequences = affect_get_u32(data + 64);
    size_t f_len = affect_get_u32(data + 68);
    rep.n_frames = affect_get_u64(data + 72);
    if (rep.iterations > cfg.max_iter)
        return affect_fail(err, AFFECT_ERR_FORMAT, "%u iterations exceed max_iter %u (offset 56)",
                           rep.iterations, cfg.max_iter);
    sections s;
    size_t total;
    if (!section_sizes(cfg.n_states, cfg.n_mix, cfg.dim, cfg.cov == AFFECT_HMM_FULL, &s) ||
        !blob_size(f_len, (size_t)rep.iterations + 1, &s, &total))
        return affect_fail(err, AFFECT_ERR_FORMAT, "sizes in the header overflow");
    if (size != total)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "%s: %zu bytes, expected %zu for %u states x %u mixtures x %u "
                           "dimensions",
                           size < total ? "truncated" : "trailing bytes", size, total, cfg.n_states,
                           cfg.n_mix, cfg.dim);
    if (!affect_checksum_ok(data, size - 8))
        return affect_fail(err, AFFECT_ERR_FORMAT, "model checksum mismatch: the BLOB is corrupt");

    /* contents: the hash matched, so these fail only for a BLOB written wrongly */
    const char *msg = affect_hmm_config_check(&cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_FORMAT, "bad configuration: %s", msg);
    affect_features *feat = NULL;
    affect_hmm *model = NULL;
    double *ll = NULL, *par = NULL;
    size_t off = AFFECT_HMM_BLOB_HEADER_SIZE;
    affect_error ferr;
    affect_status st = affect_features_decode(data + off, f_len, &feat, &ferr);
    if (st) {
        if (st == AFFECT_ERR_NOMEM)
            st = affect_nomem(err);
        else
            st = affect_fail(err, AFFECT_ERR_FORMAT, "feature definition at offset %zu: %s", off,
                             ferr.msg);
        goto fail;
    }
    if (affect_features_dim(feat) != cfg.dim) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "the feature definition gives %u dimensions, the header %u",
                         affect_features_dim(feat), cfg.dim);
        goto fail;
    }
    off += f_len;
    ll = affect_malloc_array((size_t)rep.iterations + 1, sizeof *ll);
    par = affect_malloc_array(s.total, sizeof *par);
    if (!ll || !par) {
        st = affect_nomem(err);
        goto fail;
    }
    double *start = par, *trans = start + s.start, *w = trans + s.trans, *mu = w + s.weights,
           *cov = mu + s.means;
    if ((st = get_doubles(data, &off, ll, (size_t)rep.iterations + 1, "log-likelihoods", err)) ||
        (st = get_doubles(data, &off, start, s.start, "start probabilities", err)) ||
        (st = get_doubles(data, &off, trans, s.trans, "transitions", err)) ||
        (st = get_doubles(data, &off, w, s.weights, "mixture weights", err)) ||
        (st = get_doubles(data, &off, mu, s.means, "means", err)) ||
        (st = get_doubles(data, &off, cov, s.covs, "covariances", err)))
        goto fail;
    st = affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &model, &ferr);
    if (st) {
        if (st == AFFECT_ERR_NOMEM)
            st = affect_nomem(err);
        else
            st = affect_fail(err, AFFECT_ERR_FORMAT, "bad parameters: %s", ferr.msg);
        goto fail;
    }
    rep.loglik = ll;
    if ((st = affect_hmm_set_report(model, &rep, err)) != AFFECT_OK)
        goto fail;
    affect_free(ll);
    affect_free(par);
    *h = model;
    *f = feat;
    return AFFECT_OK;
fail:
    affect_hmm_free(model);
    affect_features_free(feat);
    affect_free(ll);
    affect_free(par);
    return st;
}

/* A path's derivative state and the derivative films' splat (include/dartspp/derivative.h;
 * docs/derivatives.md §3). Forward mode with the sampled path held fixed: every factor of the path
 * contribution f that depends on a parameter adds its log-derivative to deriv_path.dlog; the time of
 * flight's derivative collects in deriv_path.dtof; the correlated importance's log-derivative is added
 * where a contribution lands (Yi et al. 2021 eqs. 7–13). */
#include <stdlib.h>

#include "dartspp/derivative.h"

int deriv_plan_init(deriv_plan *d, const scene *s, dp_error *err)
{
    *d = (deriv_plan){.s = s, .count = s->diff_count, .param = s->diffs,
                      .camera_unwarp = s->integrator.window.camera_unwarp};
    if (d->count == 0 || s->light_count == 0) return 0;
    d->kernel = calloc((size_t)s->light_count, sizeof *d->kernel);
    if (!d->kernel) return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory for the derivatives' time kernels");
    for (int i = 0; i < s->light_count; i++) d->kernel[i] = (time_kernel){s->lights[i].pulse, &s->cam.response};
    if (deriv_geometry_init(d, s, err)) {
        deriv_plan_free(d);
        return -1;
    }
    return 0;
}

void deriv_plan_free(deriv_plan *d)
{
    free(d->kernel);
    d->kernel = NULL;
    deriv_geometry_free(d);
}

void deriv_transmittance(const deriv_plan *d, deriv_path *p, int med, double len)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_MEDIUM && q->index == med) /* ∂ ln e^{−σt·ℓ} = −ℓ·∂σt */
            p->dlog[k] = v3_sub(p->dlog[k], v3_scale(v3_add(q->dsigma_s, q->dsigma_a), len));
    }
}

void deriv_time(const deriv_plan *d, deriv_path *p, int med, double len)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_MEDIUM && q->index == med) p->dtof[k] += len * q->deta; /* Yi eq. 13: η̇·|x_i − x_{i−1}| */
    }
}

/* ∂σs/σs per channel, 0 where σs does not move (a channel of σs = 0 that moves is refused at load). */
static vec3 dlog_sigma_s(const medium *m, vec3 ds)
{
    vec3 r = v3s(0.0);
    if (ds.x != 0.0) r.x = ds.x / m->sigma_s.x;
    if (ds.y != 0.0) r.y = ds.y / m->sigma_s.y;
    if (ds.z != 0.0) r.z = ds.z / m->sigma_s.z;
    return r;
}

void deriv_medium_vertex(const deriv_plan *d, deriv_path *p, int med)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_MEDIUM && q->index == med)
            p->dlog[k] = v3_add(p->dlog[k], dlog_sigma_s(&d->s->media[med], q->dsigma_s));
    }
}

/* ∂ ln p_HG(μ; g)/∂g for p_HG = (1 − g²)/(4π (1 + g² − 2gμ)^{3/2}): −2g/(1 − g²) − 3(g − μ)/(1 + g² − 2gμ). */
static double hg_dlog_dg(double g, double mu)
{
    return -2.0 * g / (1.0 - g * g) - 3.0 * (g - mu) / (1.0 + g * g - 2.0 * g * mu);
}

void deriv_phase(const deriv_plan *d, deriv_path *p, int med, vec3 w_in, vec3 w_out)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_PHASE_G && q->index == med)
            p->dlog[k] = v3_add(p->dlog[k], v3s(hg_dlog_dg(d->s->media[med].phase.g, v3_dot(w_in, w_out))));
    }
}

void deriv_surface_vertex(const deriv_plan *d, deriv_path *p, int b)
{
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        if (q->kind == DIFF_ALBEDO && q->index == b) p->dlog[k] = v3_add(p->dlog[k], q->dlog);
    }
}

/* ---- the correlated importance of one box ----
 * S(τ) = (F(b − τ) − F(a − τ))/W for the box [a, b) of width W (its weight 1/W: the gate image or a frame;
 * Yi et al. 2021 eq. 7 with W_e the box and L_e the offset's distribution F). ∂S/∂θ for every way θ moves
 * it: the time of flight (∂S/∂τ·∂τ/∂θ), the pulse's start (S depends on τ + start) and width, and the box's
 * edges and width. */
typedef struct {
    double a, b, W;        /* the box */
    double da, db, dW;     /* per unit of d_start and of d_width: a' = d_start·1 + d_width·ka, ... */
    double ka, kb, kW;     /* the box's edges and width in units of the window's width */
    double S, fa, fb;      /* S(τ), f(a − τ), f(b − τ) */
} box_importance;

/* The box of the gate image (frame < 0: the whole window) or of frame k, and S at τ. */
static void box_at(const time_window *tw, long k, const time_kernel *K, double tau, box_importance *bx)
{
    int n = tw->frame_count > 0 ? tw->frame_count : 1;
    double lo = k >= 0 ? (double)k : 0.0, hi = k >= 0 ? (double)k + 1.0 : (double)n;
    bx->a = tw->start + lo * tw->width;
    bx->b = tw->start + hi * tw->width;
    bx->W = (hi - lo) * tw->width;
    bx->ka = lo, bx->kb = hi, bx->kW = hi - lo;
    bx->S = (time_kernel_cdf(K, bx->b - tau) - time_kernel_cdf(K, bx->a - tau)) / bx->W;
    bx->fa = time_kernel_pdf(K, bx->a - tau);
    bx->fb = time_kernel_pdf(K, bx->b - tau);
}

/* ∂ ln S/∂θ_k for the box (0 where S vanishes: the contribution cannot have landed there but for rounding). */
static double box_dlog(const box_importance *bx, const diff_param *q, int qlight_match, double dtof,
                       const time_kernel *K, double tau)
{
    if (!(bx->S > 0.0)) return 0.0;
    double dS_dtau = (bx->fa - bx->fb) / bx->W, dS = dS_dtau * dtof;
    switch (q->kind) {
    case DIFF_PULSE_START:
        if (qlight_match) dS += dS_dtau; /* F(x − start): S depends on τ + start */
        break;
    case DIFF_PULSE_WIDTH:
        if (qlight_match) dS += (time_kernel_dcdf_dwidth(K, bx->b - tau) - time_kernel_dcdf_dwidth(K, bx->a - tau)) / bx->W;
        break;
    case DIFF_WINDOW: {
        double da = q->d_start + bx->ka * q->d_width, db = q->d_start + bx->kb * q->d_width, dW = bx->kW * q->d_width;
        dS += (bx->fb * db - bx->fa * da) / bx->W - bx->S * dW / bx->W;
        break;
    }
    default:
        break;
    }
    return dS / bx->S;
}

/* Whether parameter q moves the path's time or its box at all (else its ∂ ln S is 0). */
static int moves_time(const diff_param *q, double dtof)
{
    return dtof != 0.0 || q->kind == DIFF_PULSE_START || q->kind == DIFF_PULSE_WIDTH || q->kind == DIFF_WINDOW;
}

/* film_slot_add with the gate image and the frame getting their own values (their boxes differ). */
static int add_layers(film *f, size_t px, const film_slot *s, vec3 vg, vec3 vf)
{
    if (!film_slot_fits(s, vg) || !film_slot_fits(s, vf)) return 0;
    double *p = &f->pass[3 * px];
    size_t plane = (size_t)f->width * f->height;
    if (s->order_layer >= 0) {
        double w = !s->gated ? 1.0 : s->k >= 0 ? s->wf : s->wg;
        vec3 v = s->k >= 0 ? vf : vg;
        float *o = &f->frame_pass[3 * (plane * (size_t)s->order_layer + px)];
        o[0] += (float)(v.x * w), o[1] += (float)(v.y * w), o[2] += (float)(v.z * w);
    }
    double wg = s->gated ? s->wg : 1.0;
    p[0] += vg.x * wg, p[1] += vg.y * wg, p[2] += vg.z * wg;
    if (s->gated && s->k >= 0) {
        float *fs = &f->frame_pass[3 * (plane * (size_t)s->k + px)];
        fs[0] += (float)(vf.x * s->wf), fs[1] += (float)(vf.y * s->wf), fs[2] += (float)(vf.z * s->wf);
    }
    return 1;
}

void deriv_splat(const deriv_plan *d, film_pixel *pix, const deriv_path *p, int light, double t, double offset,
                 vec3 c, int frame, int order)
{
    film *f = pix->f;
    if (!deriv_on(d) || f->deriv_count < d->count || v3_is_zero(c) || !v3_is_finite(c)) return;
    film_slot s = film_time_slot(f, t, frame, order);
    if (!s.counts) return;
    const time_kernel *K = light >= 0 && d->kernel ? &d->kernel[light] : NULL;
    double tau = t - offset;
    box_importance gate, fr;
    int boxes = 0;
    for (int k = 0; k < d->count; k++) {
        const diff_param *q = &d->param[k];
        vec3 dl = p->dlog[k];
        if (q->kind == DIFF_EMISSION && q->index == light) dl = v3_add(dl, q->dlog);
        double sg = 0.0, sf = 0.0;
        if (s.gated && K && moves_time(q, p->dtof[k])) {
            if (!boxes) {
                box_at(&f->window, -1, K, tau, &gate);
                if (s.k >= 0) box_at(&f->window, s.k, K, tau, &fr);
                boxes = 1;
            }
            int match = q->index == light;
            sg = box_dlog(&gate, q, match, p->dtof[k], K, tau);
            sf = s.k >= 0 ? box_dlog(&fr, q, match, p->dtof[k], K, tau) : sg;
        }
        vec3 vg = v3_mul(c, v3_add(dl, v3s(sg))), vf = v3_mul(c, v3_add(dl, v3s(sf)));
        if (!add_layers(&f->deriv[k], pix->px, &s, vg, vf)) pix->nonfinite++;
    }
}

void deriv_splat_value(const deriv_plan *d, film_pixel *pix, int k, double t, vec3 value, int frame, int order)
{
    film *f = pix->f;
    if (!deriv_on(d) || k >= f->deriv_count || v3_is_zero(value)) return;
    film_slot s = film_time_slot(f, t, frame, order);
    if (!s.counts) return;
    if (!add_layers(&f->deriv[k], pix->px, &s, value, value)) pix->nonfinite++;
}

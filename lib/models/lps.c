/*
 * lps.c -- the linear peridynamic solid (LPS), seed 000 eqs. 3-4 and
 * Algorithms 2-4 (Silling 2007), with the choices of LAMMPS peri/lps.
 *
 * With K the bulk and G the shear modulus, omega = omega(|xi|) the
 * influence function, nu_ij the partial-volume factor and e = |y_j - y_i|
 * - |xi| the extension of bond i-j:
 *   m_i     = sum_j omega |xi|^2 nu_ij V_j            weighted volume, over
 *             the reference family, once (Algorithm 3; it does not change
 *             as bonds break: seed 000, the note after eq. 4)
 *   theta_i = 3/m_i sum_{j intact} omega |xi| e nu_ij V_j   dilatation
 *             (Algorithm 4; 0 when m_i = 0)
 *   t_ij    = (3K - 5G) (omega theta_i/m_i + omega theta_j/m_j) |xi|
 *             + 15G (omega/m_i + omega/m_j) e         (Algorithm 2)
 *   f_i    += t_ij nu_ij V_j (y_j - y_i) / |y_j - y_i|
 * with e set to 0 when |e| < eps_machine (PD_NEAR_ZERO, as PMB) and no
 * force when |y_j - y_i| = 0.  Every product is taken in the order LAMMPS
 * peri/lps takes it, so both codes round alike.  Seed 000 eq. 3 writes the
 * force state as 3K theta/m omega x + alpha omega e^d with alpha = 15G/m;
 * Algorithm 2 is its pair form (with e^d = e - theta |xi|/3).
 *
 * Within one step: theta is computed from the bonds intact at the start of
 * the step; the forces use it; then each bond is tested against
 * min(s0_i, s0_j) of the previous step (seed 000 eq. 9, as PMB: a bond that
 * breaks carries its force in the step it breaks), and s0 of the next step
 * is max over the intact bonds of s00 - alpha s (eq. 9, not Algorithm 2's
 * min line, as LAMMPS).  No bond breaks at step 0 (s0 = +inf).
 *
 * Strain energy.  For a whole family the seed's W_i = K/2 theta_i^2 +
 * 15G/(2 m_i) sum_j omega (e^d)^2 nu V_j equals
 *   W*_i = (K/2 - 5G/6) theta_i^2 + 15G/(2 m_i) sum_{j intact} omega e^2 nu V_j
 * (expand (e^d)^2 and use sum omega |xi|^2 nu V = m).  pd books W* (times
 * V_i): it is the energy whose gradient is the force above also after bonds
 * break (the identity needs the whole family), so the energy balance holds.
 * When bonds break, the energy released is the drop of W* of both ends at
 * the step's positions as the bonds go.
 *
 * The influence omega may also depend on the bond's direction (the
 * ellipsoids of lib/bonds/influence.c, seed 002): omega[k] is then the bond's
 * own weight, the same in m and in every sum below.
 * VES, the viscoelastic solid (--model ves; Mitchell, SAND2011-8064, as
 * LAMMPS peri/ves).  The deviatoric extension of directed bond i-j,
 *   e^d = e - theta_i |xi| / 3      (theta of i only, as LAMMPS),
 * splits into an elastic spring and a Maxwell branch of weight lambda with
 * the back extension e^b (the dashpot's share).  With the relaxation time
 * tau and c = tau/dt, d = exp(-1/c), beta = 1 - c (1 - d), the exact
 * integral of de^b/dt = (e^d - e^b)/tau over a step with e^d linear in time
 * gives
 *   e^b_{n+1} = e^d_n (1 - d) + e^b_n d + beta (e^d_{n+1} - e^d_n)
 * and the pair force
 *   t_ij = 3K (omega theta_i/m_i + omega theta_j/m_j) |xi| nu V_j
 *        + 15G (omega/m_i + omega/m_j) [(1 - lambda) e^d + lambda (e^d -
 *          e^b_{n+1})] nu V_j.
 * e^d_n and e^b_n are kept per directed bond (the bond history, in the
 * restart slots) and advance at every force evaluation but step 0's.  With
 * lambda = 0 this is LPS but for one thing LAMMPS does: the deviatoric
 * part of t_ij uses theta_i for both ends, where Algorithm 2 has theta_i/m_i
 * + theta_j/m_j; so t_ij != t_ji where theta_i != theta_j and m_i != m_j
 * (near a surface or a crack), and momentum is not conserved to rounding
 * there.  pd follows LAMMPS (to agree with peri/ves to 1e-9).  The elastic
 * energy booked is LAMMPS's
 *   W_i = K/2 theta_i^2 + 15G/(2 m_i) sum_{j intact} omega [(1 - lambda)
 *         (e^d)^2 + lambda (e^d - e^b)^2] nu V_j,
 * the energy of the springs; the dashpot dissipates, which the status
 * line's balance does not book (it drifts by what the dashpot took).
 *
 * EPS, the elastic-plastic solid (--model eps; Mitchell, SAND2011-3166,
 * with the plastic update corrected; pd-run(1) MODELS derives it and says
 * what LAMMPS peri/eps differs in).  Each directed bond keeps a plastic
 * extension e^p.  Particle i's trial deviatoric force state is
 *   t^d = alpha_i omega (e^d - e^p_n),  alpha_i = 15G/m_i,
 * |t^d|^2 = sum_j (t^d)^2 nu V_j; with the yield value psi_0 = 5/2 Y^2
 * I_i/m_i^2, I_i = sum_j omega^2 |xi|^2 nu V_j (von Mises in the continuum:
 * Mitchell's 25 Y^2/(8 pi delta^5) for omega = 1), a particle with
 * |t^d|^2/2 > psi_0 scales its state back by r_i = sqrt(2 psi_0)/|t^d| and
 *   e^p_{n+1} = e^d - r_i (e^d - e^p_n)
 * (Mitchell's e^p += Delta-lambda t^d with omega divided out).  The pair
 * force is the state form T_i<xi> - T_j<-xi>,
 *   t_ij = 3K (omega theta_i/m_i + omega theta_j/m_j) |xi| nu V_j
 *        + 15G omega [r_i (e^d_ij - e^p_ij)/m_i + r_j (e^d_ji - e^p_ji)/m_j] nu V_j
 * with e^d_ji = e - theta_j |xi|/3: t_ij = t_ji, and below yield it is
 * Algorithm 2 rearranged (LPS to rounding).  The trial norms are taken
 * over the bonds intact at the start of the step, the forces use the old
 * e^p and r, and e^p advances after every row has read it (not at step 0).
 * The elastic energy booked is W_i = K/2 theta_i^2 + 15G/(2 m_i) sum
 * omega (e^d - e^p)^2 nu V_j; the plastic dissipation is not booked.
 *
 * Each particle walks its own (directed) family and writes only its own
 * force, theta, s0 and bond history: no scatter, so the sums are in a
 * fixed order and the result does not depend on the thread count.
 *
 * Storage.  The walk reads the file's directed bonds (neighbor, |xi|, nu)
 * and the run's directed state bits mu (sim->intact, the copy pd_sim_intact
 * keeps; bit k is bond k's, so the walk reads the bits in order and needs
 * no map to the half bonds).  A bond that breaks is cleared in both of its
 * directed copies and in the run's half bonds (sim->half.intact, which the
 * run counts and writes), found by a search, as breaking is rare.
 * omega is stored per directed bond only when it depends on the bond's
 * direction (ellipsoids); otherwise it is omega(|xi|), computed where it is
 * used from the bond's length (the same double as a stored one).  Per
 * directed bond LPS keeps 1 bit (the breaks of this step); VES adds 16 B
 * (e^d_n, e^b_n), EPS 16 B (e^p, the reverse bond).  Each thread has a
 * scratch of a few rows of the largest family, where the kernel puts one
 * family's bond terms before it sums them (see theta_fast).
 */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "models/model.h"
#include "stencil/grid.h"

typedef struct {
    double *m;         /* n: weighted volume m_i, m^5 times omega's unit */
    double *theta;     /* n: dilatation of this step                     */
    double *omega;     /* directed bonds: omega(|xi|) d(xi/|xi|) with
                          ellipsoids; NULL: omega(|xi|), see weight()    */
    pd_influence influence; /* omega(|xi|) of the scene                 */
    uint64_t *kill;    /* directed bonds, bits: breaks in this step      */
    uint64_t *before;  /* directed bonds, bits: the state before them    */
    uint8_t *touched;  /* n: particle with a bond breaking in this step  */
    double *released;  /* n: energy released at each particle, J         */
    pd_model_kind model; /* PD_MODEL_LPS, PD_MODEL_VES or PD_MODEL_EPS   */
    double *hist;      /* VES: 2 per directed bond, e^d_n and e^b_n;
                          EPS: 1, the plastic extension e^p              */
    int64_t *rev;      /* EPS: directed bond i-j -> j-i                  */
    double *psi0;      /* EPS: n, the yield value psi_0 of each particle */
    double *ratio;     /* EPS: n, sqrt(2 psi_0)/|t^d_trial| (1: elastic) */
    double decay, beta;/* VES: d = exp(-dt/tau), beta = 1 - tau/dt (1 - d) */
    int nthreads;      /* threads of the kernel, each with its scratch   */
    int64_t family;    /* the largest family, directed bonds             */
    double *scratch;   /* nthreads x LPS_ROWS x family: one row's terms  */
} lps_state;

/* The row arrays of a thread's scratch: omega, then six bond terms. */
#define LPS_ROWS 7

void pd_lps_weighted_volume(const pd_particles *p, const pd_bonds *b, pd_influence w, double *m)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < b->n; i++) {
        double sum = 0;
        pd_bond_iter it;
        for (pd_family_start(b, p, i, &it); pd_family_next(&it);) {
            const int32_t j = it.j;
            const double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                         dz = p->x[2][i] - p->x[2][j];
            const double rsq = dx * dx + dy * dy + dz * dz;
            sum += pd_lps_influence(w, it.length, b->horizon) * rsq * p->volume[j] * it.vfactor;
        }
        m[i] = sum;
    }
}

/* omega of directed bond k: the stored one (ellipsoids) or omega(|xi|). */
static inline double weight(const lps_state *st, const pd_bonds *b, int64_t k)
{
    return st->omega ? st->omega[k] : pd_lps_influence(st->influence, b->length[k], b->horizon);
}

/* The weight of every directed bond, omega[k] = omega(|xi|) d(xi/|xi|)
 * (lib/bonds/influence.c: d = 1 without ellipsoids), and m_i from it (Algorithm
 * 3, in pd_lps_weighted_volume's order of products); omega NULL: m only.
 * With S (pd_lps_stable_dt's) also S_i = sum_j omega |xi| nu V_j.  Each
 * family whole (pd_family_get: compact families walked off their stencil
 * without a call a bond).  Returns 0, or -1 out of memory. */
static int bond_weights(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                        double *omega, double *m, double *S)
{
    int bad = 0;
#pragma omp parallel reduction(| : bad)
    {
        pd_family_buf fb = {0};
#pragma omp for schedule(static)
        for (int64_t i = 0; i < b->n; i++) {
            pd_family f;
            bad |= pd_family_get(b, p, i, &fb, &f) != 0;
            double sum = 0, sl = 0;
            for (int64_t t = 0; t < f.n; t++) {
                const int32_t j = f.j[t];
                const double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
                             dz = p->x[2][i] - p->x[2][j];
                const double rsq = dx * dx + dy * dy + dz * dz, xi[3] = {-dx, -dy, -dz};
                const double om = pd_bond_influence(s, f.length[t], b->horizon, xi);
                if (omega != NULL)
                    omega[f.first + t] = om;
                sum += om * rsq * p->volume[j] * f.vfactor[t];
                if (S != NULL)
                    sl += om * f.length[t] * f.vfactor[t] * p->volume[j];
            }
            m[i] = sum;
            if (S != NULL)
                S[i] = sl;
        }
        pd_family_buf_free(&fb);
    }
    return bad ? -1 : 0;
}

/* omega of bond t of row i's family f, as bond_weights has it. */
static double bond_omega(const pd_particles *p, const pd_bonds *b, const pd_scene *s, int64_t i,
                         const pd_family *f, int64_t t)
{
    const int32_t j = f->j[t];
    const double xi[3] = {-(p->x[0][i] - p->x[0][j]), -(p->x[1][i] - p->x[1][j]),
                          -(p->x[2][i] - p->x[2][j])};
    return pd_bond_influence(s, f->length[t], b->horizon, xi);
}

static void lps_free(void *state)
{
    lps_state *st = state;
    if (st == NULL)
        return;
    free(st->m);
    free(st->theta);
    free(st->omega);
    free(st->kill);
    free(st->before);
    free(st->touched);
    free(st->released);
    free(st->hist);
    free(st->rev);
    free(st->psi0);
    free(st->ratio);
    free(st->scratch);
    free(st);
}

/* EPS: the reverse of each directed bond (the two directed bonds of a
 * half bond point at each other), and psi_0 = 5/2 Y^2 I_i / m_i^2 with
 * I_i = sum_j omega^2 |xi|^2 nu V_j (see the top). */
static pd_status eps_init(const pd_sim *sim, lps_state *st)
{
    const pd_bonds *b = sim->b;
    const double Y = sim->sc.yield_stress;
    const pd_half_bonds *h = &sim->half;
    const int64_t nh = h->count;
    int64_t *first = malloc((size_t)(nh > 0 ? nh : 1) * sizeof(int64_t));
    if (first == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the EPS state of %lld bonds",
                       (long long)b->count);
    for (int64_t q = 0; q < nh; q++)
        first[q] = -1;
    /* the half bond of each directed bond: row i meets its bonds to j < i
     * in ascending i for each j, so a cursor per row finds them */
    for (int64_t i = 0; i < sim->n; i++)
        h->cursor[i] = h->offset[i];
    for (int64_t i = 0; i < sim->n; i++) {
        int64_t own = h->offset[i];
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            const int32_t j = b->neighbor[k];
            const int64_t q = j < i ? h->cursor[j]++ : own++;
            if (first[q] < 0)
            first[q] = k;
            else {
                st->rev[k] = first[q];
                st->rev[first[q]] = k;
            }
        }
    }
    free(first);
    for (int64_t i = 0; i < b->n; i++) {
        double I = 0;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++)
            I += weight(st, b, k) * weight(st, b, k) * b->length[k] * b->length[k] *
                 sim->p->volume[b->neighbor[k]] * b->vfactor[k];
        st->psi0[i] = st->m[i] > 0 ? 2.5 * Y * Y * I / (st->m[i] * st->m[i]) : INFINITY;
    }
    return PD_OK;
}

static pd_status lps_init(pd_sim *sim, void **state)
{
    const pd_bonds *b = sim->b;
    size_t n = (size_t)(sim->n > 0 ? sim->n : 1), nb = (size_t)(b->count > 0 ? b->count : 1);
    lps_state *st = calloc(1, sizeof *st);
    if (st == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the LPS state");
    st->m = malloc(n * sizeof(double));
    st->theta = calloc(n, sizeof(double));
    st->influence = sim->sc.influence;
    if (sim->sc.nellipsoids > 0) /* omega depends on the direction */
        st->omega = malloc(nb * sizeof(double));
    st->kill = calloc((size_t)pd_bits_words(b->count) + 1, sizeof(uint64_t));
    if (sim->sc.has_failure)
        st->before = malloc(((size_t)pd_bits_words(b->count) + 1) * sizeof(uint64_t));
    st->touched = calloc(n, 1);
    st->released = calloc(n, sizeof(double));
    if (!st->m || !st->theta || (sim->sc.nellipsoids > 0 && !st->omega) || !st->kill ||
        (sim->sc.has_failure && !st->before) || !st->touched || !st->released) {
        lps_free(st);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the LPS state of %lld bonds",
                       (long long)b->count);
    }

    st->model = sim->model->kind; /* LPS, VES or EPS (their descriptors, below) */
    const size_t width = (size_t)sim->model->history_width; /* VES 2, EPS 1 */
    if (st->model == PD_MODEL_EPS) {
        st->hist = calloc(width * nb, sizeof(double));
        st->rev = malloc(nb * sizeof(int64_t));
        st->psi0 = malloc(n * sizeof(double));
        st->ratio = malloc(n * sizeof(double));
        if (!st->hist || !st->rev || !st->psi0 || !st->ratio) {
            lps_free(st);
            return pd_fail(PD_ERR_NOMEM, "out of memory for the EPS state of %lld bonds",
                           (long long)b->count);
        }
        for (int64_t i = 0; i < sim->n; i++)
            st->ratio[i] = 1.0;
    }
    if (st->model == PD_MODEL_VES) {
        const double c1 = sim->sc.ves_tau / sim->sc.dt;
        st->decay = exp(-1.0 / c1);
        st->beta = 1.0 - c1 * (1.0 - st->decay);
        if ((st->hist = calloc(width * nb, sizeof(double))) == NULL) {
            lps_free(st);
            return pd_fail(PD_ERR_NOMEM, "out of memory for the VES history of %lld bonds",
                           (long long)b->count);
        }
    }
    st->nthreads = omp_get_max_threads();
    for (int64_t i = 0; i < sim->n; i++)
        if (b->offset[i + 1] - b->offset[i] > st->family)
            st->family = b->offset[i + 1] - b->offset[i];
    st->scratch = malloc((size_t)st->nthreads * LPS_ROWS * (size_t)(st->family > 0 ? st->family : 1) *
                         sizeof(double));
    if (st->scratch == NULL) {
        lps_free(st);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the LPS scratch");
    }
    if (bond_weights(sim->p, b, &sim->sc, st->omega, st->m, NULL) != 0) {
        lps_free(st);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the LPS weights");
    }
    /* the directed bits from the half bonds, so that both copies of a bond
     * agree (the file's bits may not) */
    sim->intact_stale = 1;
    (void)pd_sim_intact(sim);
    pd_status es = st->model == PD_MODEL_EPS ? eps_init(sim, st) : PD_OK;
    if (es != PD_OK) {
        lps_free(st);
        return es;
    }
    if (sim->piece) { /* a piece's ghosts lack bonds: their m (and psi_0) from their owners */
        double *a[2] = {st->m, st->psi0};
        pd_piece_exchange(sim, a, st->psi0 ? 2 : 1);
    }
    *state = st;
    return PD_OK;
}

/* |y_j - y_i| - |xi| of directed bond k of row i, 0 below eps_machine;
 * r = |y_j - y_i| and the components go back through the pointers. */
static inline double extension(const pd_sim *sim, int64_t i, int64_t k, double d[3], double *r)
{
    const int32_t j = sim->b->neighbor[k];
    d[0] = sim->y[0][j] - sim->y[0][i];
    d[1] = sim->y[1][j] - sim->y[1][i];
    d[2] = sim->y[2][j] - sim->y[2][i];
    *r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double e = *r - sim->b->length[k];
    return fabs(e) < PD_NEAR_ZERO ? 0.0 : e;
}

/* theta_i over the bonds intact in `bits` (directed bonds), Algorithm 4. */
static double theta_row(const pd_sim *sim, const lps_state *st, const uint64_t *bits, int64_t i)
{
    const pd_bonds *b = sim->b;
    const double *V = sim->p->volume;
    double sum = 0, d[3], r;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const double e = extension(sim, i, k, d, &r);
        sum += weight(st, b, k) * b->length[k] * e * V[b->neighbor[k]] * b->vfactor[k];
    }
    return st->m[i] != 0.0 ? (PD_LPS_DILATATION / st->m[i]) * sum : 0.0;
}

/* W_i of VES over the bonds intact in `bits`, theta_i = th, J/m^3, with
 * the stored back extensions (see the top). */
static double ves_energy(const pd_sim *sim, const lps_state *st, const uint64_t *bits, int64_t i,
                         double th)
{
    const pd_bonds *b = sim->b;
    const double *V = sim->p->volume,
                 lam = st->model == PD_MODEL_EPS ? 1.0 : sim->sc.ves_lambda;
    double sum = 0, d[3], r;
    const int eps = st->model == PD_MODEL_EPS; /* W of EPS: lambda = 1, e^b = e^p */
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const double ed = extension(sim, i, k, d, &r) - th * b->length[k] / 3.0;
        const double ev = ed - (eps ? st->hist[k] : st->hist[2 * k + 1]);
        sum += weight(st, b, k) * ((1.0 - lam) * ed * ed + lam * ev * ev) * V[b->neighbor[k]] *
               b->vfactor[k];
    }
    return 0.5 * sim->sc.bulk_modulus * th * th +
           0.5 * PD_LPS_SHEAR_FACTOR * sim->sc.shear_modulus / st->m[i] * sum;
}

/* Row i's sums over its bonds intact in `bits`, s[0] = sum omega e^2 nu V_j
 * (energy_row's) and t[0] = theta_row's sum, in one walk, each in the
 * family's order; with `also`, s[1] and t[1] the same over the bonds
 * intact in `also` too. */
static void row_sums(const pd_sim *sim, const lps_state *st, const uint64_t *bits,
                     const uint64_t *also, int64_t i, double s[2], double t[2])
{
    const pd_bonds *b = sim->b;
    const double *V = sim->p->volume;
    double d[3], r;
    s[0] = s[1] = t[0] = t[1] = 0;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const double e = extension(sim, i, k, d, &r), w = weight(st, b, k);
        const double vj = V[b->neighbor[k]], vf = b->vfactor[k];
        const double se = w * e * e * vj * vf, te = w * b->length[k] * e * vj * vf;
        s[0] += se;
        t[0] += te;
        if (also && pd_bond_intact(also, k)) {
            s[1] += se;
            t[1] += te;
        }
    }
}

/* V_i W*_i of LPS from row i's sums (row_sums'), m_i != 0, J. */
static double lps_row_energy(const pd_sim *sim, const lps_state *st, int64_t i, double s,
                             double t)
{
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double th = (PD_LPS_DILATATION / st->m[i]) * t; /* theta_row's */
    return sim->p->volume[i] *
           ((0.5 * K - 5.0 * G / 6.0) * th * th + 0.5 * PD_LPS_SHEAR_FACTOR * G / st->m[i] * s);
}

/* V_i W*_i over the bonds intact in `bits`, J (see the top). */
static double energy_row(const pd_sim *sim, const lps_state *st, const uint64_t *bits, int64_t i)
{
    if (st->m[i] == 0.0)
        return 0.0;
    if (st->model != PD_MODEL_LPS)
        return sim->p->volume[i] * ves_energy(sim, st, bits, i, theta_row(sim, st, bits, i));
    double s[2], t[2];
    row_sums(sim, st, bits, NULL, i, s, t);
    return lps_row_energy(sim, st, i, s[0], t[0]);
}

/* energy_row over the bits `then` less energy_row over the bits `now`
 * (each bond intact in `now` is in `then`), J: for LPS from one walk. */
static double released_row(const pd_sim *sim, const lps_state *st, const uint64_t *then,
                           const uint64_t *now, int64_t i)
{
    if (st->model != PD_MODEL_LPS || st->m[i] == 0.0)
        return energy_row(sim, st, then, i) - energy_row(sim, st, now, i);
    double s[2], t[2];
    row_sums(sim, st, then, now, i, s, t);
    return lps_row_energy(sim, st, i, s[0], t[0]) - lps_row_energy(sim, st, i, s[1], t[1]);
}

/* The VES pair force t_ij of directed bond k of row i (nu V_j included)
 * with extension e and the dilatations theta; with `advance` the bond
 * history steps to e^d_{n+1}, e^b_{n+1}, else the force uses e^b_{n+1}
 * from the stored e^d_n, e^b_n (step 0) -- see the top. */
static inline double ves_pair(const pd_sim *sim, lps_state *st, int64_t i, int64_t k, double e,
                              const double *theta, int advance)
{
    const pd_bonds *b = sim->b;
    const int32_t j = b->neighbor[k];
    const double *m = st->m, om = weight(st, b, k), len = b->length[k];
    const double w = sim->p->volume[j] * b->vfactor[k], lam = sim->sc.ves_lambda;
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double td = ((3.0 * K) * w * ((om * theta[i] / m[i]) + (om * theta[j] / m[j]))) * len;
    const double ed = e - (theta[i] * len / 3.0);
    double *h = st->hist + 2 * k;
    const double eb = h[0] * (1.0 - st->decay) + h[1] * st->decay + st->beta * (ed - h[0]);
    const double g = (G * w) * ((om / m[i]) + (om / m[j]));
    const double tv = ((1.0 - lam) * PD_LPS_SHEAR_FACTOR) * g * ed +
                      (lam * PD_LPS_SHEAR_FACTOR) * g * (ed - eb);
    if (advance) {
        h[0] = ed;
        h[1] = eb;
    }
    return td + tv;
}

/* The EPS pair force t_ij of directed bond k of row i (nu V_j included)
 * with extension e, the dilatations theta and the plastic extensions of
 * both directions, each deviatoric half scaled by its particle's ratio
 * (NULL: 1, the stored state) -- see the top. */
static inline double eps_pair(const pd_sim *sim, const lps_state *st, int64_t i, int64_t k,
                              double e, const double *theta, const double *ratio)
{
    const pd_bonds *b = sim->b;
    const int32_t j = b->neighbor[k];
    const double *m = st->m, om = weight(st, b, k), len = b->length[k];
    const double w = sim->p->volume[j] * b->vfactor[k];
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double td = ((3.0 * K) * w * ((om * theta[i] / m[i]) + (om * theta[j] / m[j]))) * len;
    const double di = e - (theta[i] * len / 3.0) - st->hist[k];
    const double dj = e - (theta[j] * len / 3.0) - st->hist[st->rev[k]];
    const double ri = ratio ? ratio[i] : 1.0, rj = ratio ? ratio[j] : 1.0;
    return td + (PD_LPS_SHEAR_FACTOR * G * w * om) * (ri * di / m[i] + rj * dj / m[j]);
}

/* EPS: the trial deviatoric force state of particle i, t^d = 15G/m_i omega
 * (e^d - e^p) with the stored e^p, against the yield value: ratio[i] =
 * sqrt(2 psi_0)/|t^d| where |t^d|^2/2 > psi_0, else 1. */
static void eps_yield_row(const pd_sim *sim, lps_state *st, int64_t i)
{
    const pd_bonds *b = sim->b;
    const uint64_t *bits = sim->intact; /* fresh: lps_kernel */
    const double alpha = PD_LPS_SHEAR_FACTOR * sim->sc.shear_modulus / st->m[i];
    double norm = 0, d[3], r;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const double ed = extension(sim, i, k, d, &r) - st->theta[i] * b->length[k] / 3.0;
        const double t = alpha * weight(st, b, k) * (ed - st->hist[k]);
        norm += t * t * sim->p->volume[b->neighbor[k]] * b->vfactor[k];
    }
    st->ratio[i] = st->m[i] > 0 && 0.5 * norm > st->psi0[i] ? sqrt(2.0 * st->psi0[i] / norm) : 1.0;
}

/* EPS: the return to the yield surface, e^p <- e^d - ratio_i (e^d - e^p)
 * on every intact bond of a yielding particle (after all rows read the
 * old e^p). */
static void eps_flow_row(const pd_sim *sim, lps_state *st, int64_t i)
{
    const pd_bonds *b = sim->b;
    const uint64_t *bits = sim->intact; /* fresh: lps_kernel */
    const double ri = st->ratio[i];
    if (ri == 1.0)
        return;
    double d[3], r;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const double ed = extension(sim, i, k, d, &r) - st->theta[i] * b->length[k] / 3.0;
        st->hist[k] = ed - ri * (ed - st->hist[k]);
    }
}

/* The force density on i (Algorithm 2) from theta of this step, and with
 * `failure` the breaking test (into st->kill) and s0_new[i]. */
static void force_row(pd_sim *sim, lps_state *st, int64_t i, pd_bond_mode failure)
{
    const pd_bonds *b = sim->b;
    const uint64_t *bits = sim->intact; /* fresh: lps_kernel */
    const double *V = sim->p->volume, *m = st->m, *theta = st->theta;
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double dil = PD_LPS_PAIR_FACTOR(K, G), s00 = sim->sc.s00, alpha = sim->sc.alpha;
    const double s0i = failure ? sim->s0[i] : 0;
    double fx = 0, fy = 0, fz = 0, s0_new = -INFINITY, d[3], r;
    int broke = 0;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (!pd_bond_intact(bits, k))
            continue;
        const int32_t j = b->neighbor[k];
        const double e = extension(sim, i, k, d, &r);
        const double om = weight(st, b, k), len = b->length[k];
        double fb;
        if (st->model == PD_MODEL_VES) {
            fb = ves_pair(sim, st, i, k, e, theta, !sim->setup);
            fb = r > 0.0 ? fb / r : 0.0;
        } else if (st->model == PD_MODEL_EPS) {
            fb = eps_pair(sim, st, i, k, e, theta, st->ratio);
            fb = r > 0.0 ? fb / r : 0.0;
        } else {
            double t = dil * V[j] * b->vfactor[k] *
                       ((om * theta[i] / m[i]) + (om * theta[j] / m[j])) * len;
            t += PD_LPS_SHEAR_FACTOR * (G * V[j] * b->vfactor[k]) * ((om / m[i]) + (om / m[j])) * e;
            fb = r > 0.0 ? t / r : 0.0;
        }
        fx += d[0] * fb;
        fy += d[1] * fb;
        fz += d[2] * fb;
        if (failure) {
            const double s = e / len;
            if (s > fmin(s0i, sim->s0[j])) {
#pragma omp atomic
                st->kill[k >> 6] |= UINT64_C(1) << (k & 63);
                broke = 1;
            }
            s0_new = fmax(s0_new, s00 - (alpha * s));
        }
    }
    sim->f[0][i] += fx;
    sim->f[1][i] += fy;
    sim->f[2][i] += fz;
    if (failure) {
        sim->s0_new[i] = s0_new == -INFINITY ? DBL_MAX : s0_new; /* no intact bond: +inf */
        st->touched[i] = (uint8_t)broke;
    }
}

/*
 * The fast rows of the kernel.  Each row is done in two loops: the first
 * computes every bond's term into the thread's scratch with no sum across
 * bonds (so GCC vectorizes it, gathers included, and each term is rounded
 * exactly as the one-bond-at-a-time code rounds it: the same operations in
 * the same order, no contraction), a broken bond's term set to +-0; the
 * second adds the terms in the family's order.  Adding +-0 changes no sum
 * that is not -0, and these sums never are (they start at +0, and a sum of
 * two numbers rounds to -0 only when both are -0), so the result is
 * bit for bit that of theta_row and force_row, with the divisions and
 * square roots done several at a time and no branch per bond.
 */

/* omega of the cnt bonds of a row from k0 into w (or the stored ones). */
PD_VECTOR_CLONES static const double *row_weights(const lps_state *st, const pd_bonds *b,
                                                  int64_t k0, int64_t cnt, double *w)
{
    if (st->omega != NULL)
        return st->omega + k0;
    const double *len = b->length + k0;
    if (st->influence == PD_INFLUENCE_INV_R)
        for (int64_t q = 0; q < cnt; q++)
            w[q] = 1.0 / len[q]; /* pd_lps_influence, 1/r */
    else
        for (int64_t q = 0; q < cnt; q++)
            w[q] = pd_lps_influence(st->influence, len[q], b->horizon);
    return w;
}

/* Dilatation terms tt[q] = omega |xi| e nu_ij V_j of the cnt bonds of row
 * i from k0 (e as extension() has it), +0 where broken in `bits`. */
PD_VECTOR_CLONES static void theta_terms(int64_t i, int64_t k0, int64_t cnt,
                                         const uint64_t *restrict bits,
                                         const int32_t *restrict nb, const double *restrict len,
                                         const double *restrict nu, const double *restrict om,
                                         const double *restrict V, const double *restrict y0,
                                         const double *restrict y1, const double *restrict y2,
                                         double *restrict tt)
{
    for (int64_t q = 0; q < cnt; q++) {
        const int32_t j = nb[q];
        const double dx = y0[j] - y0[i], dy = y1[j] - y1[i], dz = y2[j] - y2[i];
        const double r = sqrt(dx * dx + dy * dy + dz * dz);
        double e = r - len[q];
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;
        const double t = om[q] * len[q] * e * V[j] * nu[q];
        tt[q] = (bits[(k0 + q) >> 6] >> ((k0 + q) & 63)) & 1 ? t : 0.0;
    }
}

/* LPS pair-force terms of the cnt bonds of row i from k0 (Algorithm 2, as
 * force_row): f?[q] = (y_j - y_i) t_ij / r, 0 where r = 0; with failure
 * (s0 not NULL) sv[q] = s00 - alpha s, s = e/|xi|, and kq[q] = 1 where
 * s > min(s0_i, s0_j) (the bond breaks), else 0.  A bond broken in `bits`
 * has forces +-0, sv = -inf and kq = 0. */
PD_VECTOR_CLONES static void force_terms(int64_t i, int64_t k0, int64_t cnt,
                                         const uint64_t *restrict bits,
                                         const int32_t *restrict nb, const double *restrict len,
                                         const double *restrict nu, const double *restrict om,
                                         const double *restrict V, const double *restrict y0,
                                         const double *restrict y1, const double *restrict y2,
                                         const double *restrict theta, const double *restrict m,
                                         double dil, double G, const double *restrict s0,
                                         double s00, double alpha, double *restrict fx,
                                         double *restrict fy, double *restrict fz,
                                         double *restrict sv, double *restrict kq)
{
    const double ti = theta[i], mi = m[i], s0i = s0 ? s0[i] : 0;
    for (int64_t q = 0; q < cnt; q++) {
        const int32_t j = nb[q];
        const double dx = y0[j] - y0[i], dy = y1[j] - y1[i], dz = y2[j] - y2[i];
        const double r = sqrt(dx * dx + dy * dy + dz * dz);
        double e = r - len[q];
        e = fabs(e) < PD_NEAR_ZERO ? 0.0 : e;
        const double o = om[q];
        double t = dil * V[j] * nu[q] * ((o * ti / mi) + (o * theta[j] / m[j])) * len[q];
        t += PD_LPS_SHEAR_FACTOR * (G * V[j] * nu[q]) * ((o / mi) + (o / m[j])) * e;
        const int mu = (bits[(k0 + q) >> 6] >> ((k0 + q) & 63)) & 1;
        const double rs = r > 0.0 ? r : 1.0;
        const double tr = t / rs, s = e / len[q];
        const double fb = (r > 0.0) & mu ? tr : 0.0;
        fx[q] = dx * fb;
        fy[q] = dy * fb;
        fz[q] = dz * fb;
        sv[q] = s; /* for the failure loop below */
    }
    if (s0 == NULL)
        return;
    for (int64_t q = 0; q < cnt; q++) {
        const int mu = (bits[(k0 + q) >> 6] >> ((k0 + q) & 63)) & 1;
        const double s = sv[q], s0j = s0[nb[q]], smin = s0i < s0j ? s0i : s0j;
        kq[q] = mu & (s > smin) ? 1.0 : 0.0; /* s0 is never NaN: min is fmin */
        sv[q] = mu ? s00 - (alpha * s) : -INFINITY;
    }
}

/* theta_row with the terms of theta_terms; buf: a thread's scratch. */
static double theta_fast(const pd_sim *sim, const lps_state *st, const uint64_t *bits, int64_t i,
                         double *buf)
{
    const pd_bonds *b = sim->b;
    const int64_t k0 = b->offset[i], cnt = b->offset[i + 1] - k0;
    const double *om = row_weights(st, b, k0, cnt, buf);
    double *tt = buf + st->family;
    theta_terms(i, k0, cnt, bits, b->neighbor + k0, b->length + k0, b->vfactor + k0, om,
                sim->p->volume, sim->y[0], sim->y[1], sim->y[2], tt);
    double sum = 0;
    for (int64_t q = 0; q < cnt; q++)
        sum += tt[q];
    return st->m[i] != 0.0 ? (PD_LPS_DILATATION / st->m[i]) * sum : 0.0;
}

/* force_row of LPS with the terms of force_terms; buf: a thread's scratch. */
static void force_fast(pd_sim *sim, lps_state *st, int64_t i, pd_bond_mode failure,
                       double *buf)
{
    const pd_bonds *b = sim->b;
    const int64_t k0 = b->offset[i], cnt = b->offset[i + 1] - k0, F = st->family;
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double dil = PD_LPS_PAIR_FACTOR(K, G);
    const double *om = row_weights(st, b, k0, cnt, buf);
    double *tx = buf + F, *ty = buf + 2 * F, *tz = buf + 3 * F, *sv = buf + 4 * F,
           *kq = buf + 5 * F;
    force_terms(i, k0, cnt, sim->intact /* fresh: lps_kernel */, b->neighbor + k0,
                b->length + k0, b->vfactor + k0, om, sim->p->volume, sim->y[0], sim->y[1],
                sim->y[2], st->theta, st->m, dil, G, failure ? sim->s0 : NULL, sim->sc.s00,
                sim->sc.alpha, tx, ty, tz, sv, kq);
    double fx = 0, fy = 0, fz = 0, s0_new = -INFINITY;
    for (int64_t q = 0; q < cnt; q++) {
        fx += tx[q];
        fy += ty[q];
        fz += tz[q];
    }
    sim->f[0][i] += fx;
    sim->f[1][i] += fy;
    sim->f[2][i] += fz;
    if (!failure)
        return;
    int broke = 0;
    for (int64_t q = 0; q < cnt; q++) {
        s0_new = sv[q] > s0_new ? sv[q] : s0_new; /* fmax: sv is never NaN */
        if (kq[q] != 0.0) {
            const int64_t k = k0 + q;
#pragma omp atomic
            st->kill[k >> 6] |= UINT64_C(1) << (k & 63);
            broke = 1;
        }
    }
    sim->s0_new[i] = s0_new == -INFINITY ? DBL_MAX : s0_new; /* no intact bond: +inf */
    st->touched[i] = (uint8_t)broke;
}

/* The index of j in the ascending list a[lo..hi), or hi. */
static int64_t find32(const int32_t *a, int64_t lo, int64_t hi, int32_t j)
{
    const int64_t end = hi;
    while (lo < hi) {
        const int64_t mid = lo + (hi - lo) / 2;
        if (a[mid] < j)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < end && a[lo] == j ? lo : end;
}

/* Break the bonds the force pass marked, booking the drop of W* of every
 * particle that loses a bond (released_row, over the bits kept from
 * before the breaks and those after); returns the energy released, J.  A
 * bond breaks as its end i < j marked it (both ends do, the test being
 * symmetric): its directed copy j-i is found in j's family and its half
 * bond in i's half row (ascending). */
static double break_marked(pd_sim *sim, lps_state *st)
{
    const pd_bonds *b = sim->b;
    const pd_half_bonds *h = &sim->half;
    uint64_t *bits = sim->intact;
    memcpy(st->before, bits, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
#pragma omp parallel for schedule(dynamic, 256)
    for (int64_t i = 0; i < sim->n; i++) {
        if (!st->touched[i])
            continue;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            const int32_t j = b->neighbor[k];
            if (j < i || !pd_bond_intact(st->kill, k) || !pd_sim_may_break(sim, i, j))
                continue;
            pd_bond_break(bits, k);
            for (int64_t r = b->offset[j]; r < b->offset[j + 1]; r++)
                if (b->neighbor[r] == i)
                    pd_bond_break(bits, r);
            const int64_t q = pd_half_find(h, i, j);
            if (q >= 0)
                pd_bond_break(h->intact, q);
        }
    }
    memset(st->kill, 0, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        st->released[i] = st->touched[i] ? released_row(sim, st, st->before, bits, i) : 0.0;
        st->touched[i] = 0;
    }
    double sum; /* a piece: over its own rows, then the ranks (collective) */
    pd_sim_sum(sim, (const double *const *)&st->released, 1, &sum);
    return sum;
}

/* A bond i-j (i < j) the lattice stencil broke: marked as force_row
 * marks one, for break_marked. */
typedef struct {
    pd_sim *sim;
    lps_state *st;
    int64_t count;
} stencil_marks;

static void mark_break(void *ctx, int64_t i, int64_t j)
{
    stencil_marks *c = ctx;
    const pd_bonds *b = c->sim->b;
    const int64_t k = find32(b->neighbor, b->offset[i], b->offset[i + 1], (int32_t)j);
    if (k < b->offset[i + 1])
        c->st->kill[k >> 6] |= UINT64_C(1) << (k & 63);
    c->st->touched[i] = c->st->touched[j] = 1;
    c->count++;
}

/* The force on row i (lps_kernel's third pass); 1 when a bond of it broke. */
static inline int force_one(pd_sim *sim, lps_state *st, int64_t i, pd_bond_mode failure,
                            double *buf)
{
    if (st->model == PD_MODEL_LPS)
        force_fast(sim, st, i, failure, buf);
    else
        force_row(sim, st, i, failure);
    return failure && st->touched[i];
}

/* lps_kernel's passes for a piece of a body on MPI ranks: the same, with
 * the ghosts' theta (and EPS's ratio) from their owners between them.
 * Returns whether a bond of some rank's broke. */
static int piece_kernel(pd_sim *sim, lps_state *st, const uint64_t *bits, pd_bond_mode failure)
{
    int broke = 0;
#pragma omp parallel num_threads(st->nthreads)
    {
        double *buf = st->scratch + (size_t)omp_get_thread_num() * LPS_ROWS * (size_t)st->family;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            st->theta[i] = theta_fast(sim, st, bits, i, buf);
    }
    pd_piece_exchange(sim, &st->theta, 1);
    if (st->model == PD_MODEL_EPS) {
#pragma omp parallel for schedule(dynamic, 256)
        for (int64_t i = 0; i < sim->n; i++)
            eps_yield_row(sim, st, i);
        pd_piece_exchange(sim, &st->ratio, 1);
    }
#pragma omp parallel num_threads(st->nthreads) reduction(| : broke)
    {
        double *buf = st->scratch + (size_t)omp_get_thread_num() * LPS_ROWS * (size_t)st->family;
#pragma omp for schedule(dynamic, 256)
        for (int64_t i = 0; i < sim->n; i++)
            broke |= force_one(sim, st, i, failure, buf);
    }
    return pd_comm_or(broke);
}

static pd_status lps_kernel(pd_sim *sim, lps_state *st, pd_bond_mode failure)
{
    const uint64_t *bits = pd_sim_intact(sim); /* sim->intact, up to date */
    if (sim->grid && st->model == PD_MODEL_LPS) { /* the lattice stencil (lib/stencil/grid.c) */
        stencil_marks c = {sim, st, 0};
        pd_status s = pd_grid_lps(sim, st->m, st->theta, failure, mark_break, &c);
        const int broke = sim->piece ? pd_comm_or(c.count > 0) : c.count > 0;
        if (s == PD_OK && broke)
            sim->released += break_marked(sim, st);
        return s;
    }
    int broke = 0;
    if (sim->piece)
        broke = piece_kernel(sim, st, bits, failure);
    else
#pragma omp parallel num_threads(st->nthreads)
    {
        double *buf = st->scratch + (size_t)omp_get_thread_num() * LPS_ROWS * (size_t)st->family;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            st->theta[i] = theta_fast(sim, st, bits, i, buf);
        if (st->model == PD_MODEL_EPS) {
#pragma omp for schedule(dynamic, 256)
            for (int64_t i = 0; i < sim->n; i++)
                eps_yield_row(sim, st, i);
        }
#pragma omp for schedule(dynamic, 256) reduction(| : broke)
        for (int64_t i = 0; i < sim->n; i++)
            broke |= force_one(sim, st, i, failure, buf);
    }
    if (st->model == PD_MODEL_EPS && !sim->setup) {
#pragma omp parallel for schedule(dynamic, 256)
        for (int64_t i = 0; i < sim->n; i++)
            eps_flow_row(sim, st, i);
    }
    if (broke)
        sim->released += break_marked(sim, st);
    return PD_OK;
}

static pd_status lps_force(pd_sim *sim, void *state)
{
    return lps_kernel(sim, state, PD_BONDS_ELASTIC);
}

static pd_status lps_failure_force(pd_sim *sim, void *state)
{
    if (sim->setup) /* step 0: forces only; s0 stays +inf */
        return lps_kernel(sim, state, PD_BONDS_ELASTIC);
    pd_status st = lps_kernel(sim, state, PD_BONDS_FAILURE);
    if (st != PD_OK)
        return st;
    double *t = sim->s0;
    sim->s0 = sim->s0_new;
    sim->s0_new = t; /* sim->intact stays fresh: break_marked keeps it */
    return PD_OK;
}

static void lps_energy(const pd_sim *sim, void *state, double *e)
{
    const lps_state *st = state;
    /* on the lattice stencil its walk, which sums in another order */
    if (sim->grid && st->model == PD_MODEL_LPS && pd_grid_lps_energy(sim, st->m, e))
        return;
    const uint64_t *bits = pd_sim_intact(sim);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        e[i] += energy_row(sim, st, bits, i);
}

/* The static virial of each particle's intact bonds (pd_sim_stress):
 * s_i += 1/2 sum_j (t_ij / r) (y_j - y_i) (x) xi_ij, t_ij the pair force
 * of Algorithm 2 as force_row computes it (V_j nu included), with theta of
 * the current positions and bond states.  Each row its own sum. */
static void lps_stress(const pd_sim *sim, void *state, double *out)
{
    const lps_state *st = state;
    const pd_bonds *b = sim->b;
    const uint64_t *bits = pd_sim_intact(sim);
    const double *V = sim->p->volume, *m = st->m;
    const double K = sim->sc.bulk_modulus, G = sim->sc.shear_modulus;
    const double dil = PD_LPS_PAIR_FACTOR(K, G);
    double *const *x = sim->p->x;
    double *theta = malloc((size_t)(sim->n > 0 ? sim->n : 1) * sizeof(double));
    if (sim->piece && pd_comm_or(theta == NULL)) { /* every rank, or none, goes on */
        free(theta);
        theta = NULL;
    }
    if (theta == NULL) /* no stress rather than a wrong one */
        return;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++)
        theta[i] = theta_row(sim, st, bits, i);
    if (sim->piece) /* a ghost's family is whole on its owner (collective) */
        pd_piece_exchange((pd_sim *)sim, &theta, 1);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < sim->n; i++) {
        double sum[9] = {0}, d[3], r;
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            if (!pd_bond_intact(bits, k))
                continue;
            const int32_t j = b->neighbor[k];
            const double e = extension(sim, i, k, d, &r);
            if (!(r > 0.0))
                continue;
            const double om = weight(st, b, k), w = V[j] * b->vfactor[k];
            double t = dil * w * (om * theta[i] / m[i] + om * theta[j] / m[j]) * b->length[k] +
                       PD_LPS_SHEAR_FACTOR * G * w * (om / m[i] + om / m[j]) * e;
            if (st->model == PD_MODEL_EPS) /* with the stored plastic extensions */
                t = eps_pair(sim, st, i, k, e, theta, NULL);
            if (st->model == PD_MODEL_VES) { /* with the stored back extension */
                const double ed = e - theta[i] * b->length[k] / 3.0, lam = sim->sc.ves_lambda;
                t = 3.0 * sim->sc.bulk_modulus * w * (om * theta[i] / m[i] + om * theta[j] / m[j]) *
                        b->length[k] +
                    PD_LPS_SHEAR_FACTOR * G * w * (om / m[i] + om / m[j]) *
                        (ed - lam * st->hist[2 * k + 1]);
            }
            const double xi[3] = {x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]};
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++)
                    sum[3 * a + c] += 0.5 * t / r * d[a] * xi[c];
        }
        for (int q = 0; q < 9; q++)
            out[9 * i + q] += sum[q];
    }
    free(theta);
}

/* The bond history a restart needs: the model's history_width values per
 * directed bond (VES 2, EPS 1; none without bonds). */
static double *history_of(const pd_sim *sim, const lps_state *st, int *width)
{
    *width = !st || !st->hist || sim->b->count == 0 ? 0 : sim->model->history_width;
    return *width ? st->hist : NULL;
}

static void lps_save(const pd_sim *sim, void *state, pd_restart *r)
{
    r->bond_history = history_of(sim, state, &r->history_width);
    r->history_bonds = r->bond_history ? sim->b->count : 0;
}

static pd_status lps_restore(pd_sim *sim, void *state, const pd_restart *r)
{
    int width;
    double *hist = history_of(sim, state, &width);
    if (hist == NULL)
        return PD_OK;
    if (r->bond_history == NULL || r->history_width != width || r->history_bonds != sim->b->count)
        return pd_fail(PD_ERR_FORMAT, "the restart data have no bond history of %d values "
                       "for each of %lld directed bonds, the scene's model keeps one",
                       width, (long long)sim->b->count);
    memcpy(hist, r->bond_history, (size_t)sim->b->count * (size_t)width * sizeof(double));
    return PD_OK;
}

/* The force of a state-based model in the step's table, without and with
 * failure: the same machinery, told apart by lps_state.model. */
#define LPS_EFFECT(NAME, FORCE)                                                                    \
    {.name = NAME, .timer = PD_T_BONDS, .init = lps_init, .force = FORCE, .free = lps_free,       \
     .energy = lps_energy, .kind = PD_ENERGY_ELASTIC, .stress = lps_stress, .save = lps_save,      \
     .restore = lps_restore}
const pd_effect pd_effect_lps = LPS_EFFECT("lps", lps_force);
const pd_effect pd_effect_lps_failure = LPS_EFFECT("lps+failure", lps_failure_force);
const pd_effect pd_effect_ves = LPS_EFFECT("ves", lps_force);
const pd_effect pd_effect_ves_failure = LPS_EFFECT("ves+failure", lps_failure_force);
const pd_effect pd_effect_eps = LPS_EFFECT("eps", lps_force);
const pd_effect pd_effect_eps_failure = LPS_EFFECT("eps+failure", lps_failure_force);

/* The state of the run's LPS-family effect, or NULL. */
static lps_state *lps_of(const pd_sim *sim)
{
    for (int k = 0; k < sim->neffects; k++)
        if (sim->effects[k]->init == lps_init)
            return sim->state[k];
    return NULL;
}

double *pd_sim_bond_history(const pd_sim *sim, int *width)
{
    return history_of(sim, lps_of(sim), width);
}

pd_status pd_sim_dilatation(const pd_sim *sim, double *theta)
{
    const lps_state *st = lps_of(sim);
    if (st != NULL) {
        const uint64_t *bits = pd_sim_intact(sim);
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < sim->n; i++)
            theta[i] = theta_row(sim, st, bits, i);
        return PD_OK;
    }
    return pd_fail(PD_ERR_INVALID, "the run has no LPS model, so no dilatation");
}

/*
 * The stable step, in the form of seed 004 eq. 46, dt < sqrt(2 rho_i /
 * sum_p V_p C_ip), with C_ip bounding the stiffness that particle p's
 * displacement puts on i (eq. 46 is Gershgorin's bound on the PMB
 * stiffness rows).  The deviatoric term of the LPS pair force is a bond
 * of stiffness 15G omega (1/m_i + 1/m_p) nu per unit extension; the
 * dilatation term couples i to p through theta_i and theta_p, with
 * |d theta_q / d u| <= 3/m_q (S_q + the bond's share), S_q = sum omega
 * |xi| nu V over q's family.  Together:
 *   C_ip = omega nu [15G (1/m_i + 1/m_p) + 3 |3K - 5G| |xi| (S_i/m_i^2 + S_p/m_p^2)]
 * For G = 3K/5 (Poisson ratio 1/4) in an interior family with omega =
 * 1/|xi| this is PMB's c/|xi| with c = 18K/(pi delta^4).
 */
double pd_lps_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    const int64_t n = b->n;
    double *m = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    double *S = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
    if (m == NULL || S == NULL) {
        free(m);
        free(S);
        return NAN;
    }
    if (bond_weights(p, b, s, NULL, m, S) != 0) {
        free(m);
        free(S);
        return NAN;
    }
    /* VES (see the top): theta_i enters t_ij with 3K omega/m_i - 5G omega
     * (1/m_i + 1/m_j), theta_j with 3K omega/m_j; with m_i ~ m_j both are
     * bounded by max(3K, 10G - 3K) omega/m, which takes the place of
     * |3K - 5G| */
    const double G = s->shear_modulus,
                 dil = s->model == PD_MODEL_VES
                           ? fmax(3.0 * s->bulk_modulus, 10.0 * G - 3.0 * s->bulk_modulus)
                           : fabs(3.0 * s->bulk_modulus - 5.0 * G);
    double best = INFINITY;
    int bad = 0;
    /* a window's own rows (pd_read_body_ranks), whose partners' families
     * are whole; the other rows' are their ranks' */
    const int64_t lo = p->window ? p->own_lo : 0, hi = p->window ? p->own_hi : n;
#pragma omp parallel reduction(min : best) reduction(| : bad)
    {
        pd_family_buf fb = {0};
#pragma omp for schedule(static)
        for (int64_t i = lo; i < hi; i++) {
            pd_family f;
            bad |= pd_family_get(b, p, i, &fb, &f) != 0;
            double sum = 0;
            for (int64_t t = 0; t < f.n; t++) {
                const int32_t j = f.j[t];
                if (m[j] == 0) { /* a partner whose family b lacks (a piece's rows
                                    alone, pd_read_bonds_rows): its rank's row */
                    sum = 0;
                    break;
                }
                const double om = bond_omega(p, b, s, i, &f, t);
                const double C =
                    om * f.vfactor[t] *
                    (PD_LPS_SHEAR_FACTOR * G * (1.0 / m[i] + 1.0 / m[j]) +
                     3.0 * dil * f.length[t] * (S[i] / (m[i] * m[i]) + S[j] / (m[j] * m[j])));
                sum += p->volume[j] * C;
            }
            if (sum > 0)
                best = fmin(best, sqrt(2.0 * p->density[i] / sum));
        }
        pd_family_buf_free(&fb);
    }
    free(m);
    free(S);
    return bad ? NAN : best;
}

/* The radial influence of LPS on a lattice: the stencil's LPS kernels;
 * ellipsoids, VES and EPS walk the bond lists. */
static pd_stencil_kind lps_stencil(const pd_scene *s)
{
    return s->nellipsoids > 0 ? PD_STENCIL_NONE : PD_STENCIL_LPS;
}

static pd_stencil_kind no_stencil(const pd_scene *s)
{
    (void)s;
    return PD_STENCIL_NONE;
}

static const char *const lps_needs[] = {"--bulk-modulus", "--shear-modulus", NULL};
static const char *const ves_needs[] = {"--bulk-modulus", "--shear-modulus", "--ves-lambda",
                                        "--ves-tau", NULL};
static const char *const eps_needs[] = {"--bulk-modulus", "--shear-modulus", "--yield-stress",
                                        NULL};
static const char *const lps_takes[] = {"--influence", "--ellipsoid", NULL};
static const pd_model_param ves_params[] = {
    {"ves-lambda", "ves_lambda", offsetof(pd_scene, ves_lambda)},
    {"ves-tau", "ves_tau", offsetof(pd_scene, ves_tau)},
    {NULL, NULL, 0}};
static const pd_model_param eps_params[] = {
    {"yield-stress", "yield_stress", offsetof(pd_scene, yield_stress)}, {NULL, NULL, 0}};

static void lps_describe(const pd_scene *sc, char *text, size_t len)
{
    snprintf(text, len,
             "model lps (seed 000 eqs. 3-4, Algorithms 2-4): K %g Pa, G %g Pa, influence %s; "
             "contact stiffness from c = 18K/(pi delta^4)",
             sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence));
}

static void ves_describe(const pd_scene *sc, char *text, size_t len)
{
    snprintf(text, len,
             "model ves (Mitchell SAND2011-8064, as LAMMPS peri/ves): K %g Pa, G %g Pa, "
             "influence %s, lambda %g, tau %g s; contact stiffness from c = 18K/(pi delta^4)",
             sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence),
             sc->ves_lambda, sc->ves_tau);
}

static void eps_describe(const pd_scene *sc, char *text, size_t len)
{
    snprintf(text, len,
             "model eps (Mitchell SAND2011-3166, a corrected plastic update; see pd-run(1)): K "
             "%g Pa, G %g Pa, influence %s, yield stress %g Pa; contact stiffness from c = "
             "18K/(pi delta^4)",
             sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence),
             sc->yield_stress);
}

const pd_model pd_model_lps = {
    .name = "lps", .kind = PD_MODEL_LPS, .state_based = 1, .force = &pd_effect_lps,
    .force_failure = &pd_effect_lps_failure, .stable_dt = pd_lps_stable_dt,
    .stencil = lps_stencil, .needs = lps_needs, .takes = lps_takes,
    .fields = PD_FIELD_ENERGY | PD_FIELD_STRESS, .describe = lps_describe};
const pd_model pd_model_ves = {
    .name = "ves", .kind = PD_MODEL_VES, .state_based = 1, .force = &pd_effect_ves,
    .force_failure = &pd_effect_ves_failure, .stable_dt = pd_lps_stable_dt,
    .stencil = no_stencil, .dissipative = 1, .history_width = 2, .needs = ves_needs, .takes = lps_takes,
    .fields = PD_FIELD_ENERGY | PD_FIELD_STRESS, .params = ves_params,
    .describe = ves_describe};
const pd_model pd_model_eps = {
    .name = "eps", .kind = PD_MODEL_EPS, .state_based = 1, .force = &pd_effect_eps,
    .force_failure = &pd_effect_eps_failure, .stable_dt = pd_lps_stable_dt,
    .stencil = no_stencil, .dissipative = 1, .history_width = 1, .needs = eps_needs, .takes = lps_takes,
    .fields = PD_FIELD_ENERGY | PD_FIELD_STRESS, .params = eps_params,
    .describe = eps_describe};

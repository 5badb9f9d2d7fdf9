/*
 * runfile.c -- the file protocol of a run (pd-run, or a program of a
 * user's own): a new run file holds the model it started from, the
 * resolved scene and every frame laid out before the first step, then it is
 * published under its final name, so that a run killed at any moment leaves
 * a readable file of complete frames; each frame is written with the
 * restart data of its step; a restart goes on from the last complete
 * frame, bit for bit (schema.c on the slots).
 */
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "io/h5util.h"
#include "models/model.h"
#include "pd.h"
#include "stencil/grid.h"

/* A lattice body's windows (pd_read_body_ranks): *p, *b NULL (on every
 * rank) where they cannot stand for the whole body. */
static pd_status read_lattice_window(const pd_file *f, const pd_scene *sc,
                                     const pd_particles *share, pd_particles **pout,
                                     pd_bonds **bout, pd_body_read *w)
{
    const pd_model *model = pd_model_of(sc->model);
    if (model == NULL || model->stencil(sc) == PD_STENCIL_NONE || sc->bond_list)
        return PD_OK; /* the same on every rank: no stencil walks it */
    pd_stencil *st = pd_read_stencil(f);
    int64_t r[6]; /* the piece's rows, its own, the window's */
    int ok = pd_comm_min(st != NULL) == 1 && pd_piece_lattice_rows(share, st, r);
    pd_stencil_free(st);
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    int64_t first = 0;
    pd_status s = ok ? pd_comm_agree(pd_read_particles_rows(f, pd_body_count(share), r[4], r[5],
                                                             &p))
                     : PD_OK;
    if (s == PD_OK && ok) {
        p->own_lo = r[2] - r[4];
        p->own_hi = r[3] - r[4];
        s = pd_read_bonds_window(f, p, r[0] - r[4], r[1] - r[4], &b, &first);
    }
    if (s == PD_OK && b && pd_piece_lattice_fits(p, b, sc)) {
        *pout = p;
        *bout = b;
        *w = (pd_body_read){2, first, b->offset[r[0] - r[4]], b->offset[r[1] - r[4]] -
                                                                  b->offset[r[0] - r[4]]};
        return PD_OK;
    }
    pd_particles_free(p);
    pd_bonds_free(b);
    return s;
}

pd_status pd_read_body_ranks(const pd_file *f, const pd_scene_spec *o, pd_particles **pout,
                             pd_bonds **bout, pd_body_read *w)
{
    /* the scene as far as the stencil's walk is concerned: with its laws,
     * which pd_scene_resolve gives it later */
    pd_scene scene = o->sc;
    scene.nlaws = o->nlaws;
    scene.laws = o->laws;
    const pd_scene *sc = &scene;
    *pout = NULL;
    *bout = NULL;
    *w = (pd_body_read){0, 0, 0, 0};
    /* each rank its share of the rows, checked: the ids over the ranks, and
     * whether the body is off any lattice (collective) */
    const int64_t P = pd_comm_size(), me = pd_comm_rank();
    int64_t n = 0;
    pd_particles *share = NULL;
    pd_status s = pd_file_particles(f, &n);
    if (s == PD_OK)
        s = pd_read_particles_rows(f, n, n * me / P, n * (me + 1) / P, &share);
    s = pd_comm_agree(s);
    if (s == PD_OK)
        s = pd_comm_agree(pd_check_ids_ranks(f, share));
    const int lists = s == PD_OK && pd_file_bonds_listed(f);
    if (s == PD_OK && lists)
        w->rows = pd_piece_reads_rows(share, sc);
    else if (s == PD_OK && P > 1) /* a lattice's stencil: windows where they show it */
        s = read_lattice_window(f, sc, share, pout, bout, w);
    if (s != PD_OK || *pout) {
        pd_particles_free(share);
        return s;
    }
    if (!w->rows) { /* the whole body (a lattice's stencil) */
        pd_particles_free(share);
        if (s == PD_OK)
            s = pd_read_particles(f, pout);
        if (s == PD_OK)
            s = pd_read_bonds_compact(f, *pout, bout);
        return s;
    }
    /* the largest span of a bond, each rank over its share of the rows;
     * then this rank's piece: its rows' bonds, and the particles they reach */
    int64_t span = 1, g0 = 0, g1 = 0, o0 = 0, o1 = 0, first_bond = 0;
    s = pd_file_has_bonds(f) ? PD_OK
                             : pd_fail(PD_ERR_FORMAT, "'%s' has no /bonds (run pd-bonds first)",
                                       f->name);
    if (s == PD_OK)
        s = pd_read_bonds_span(f, n, share->first, share->first + share->n, &span);
    pd_particles_free(share);
    s = pd_comm_agree(s);
    span = -pd_comm_min(-span);
    if (s == PD_OK)
        s = pd_piece_rows(n, span, &g0, &g1, &o0, &o1);
    pd_particles *p = NULL;
    if (s == PD_OK)
        s = pd_read_particles_rows(f, n, g0 - span > 0 ? g0 - span : 0,
                                   g1 + span < n ? g1 + span : n, &p);
    if (s == PD_OK) {
        p->own_lo = o0 - p->first;
        p->own_hi = o1 - p->first;
        s = pd_read_bonds_rows(f, p, g0, g1, bout, &first_bond);
    }
    if (s != PD_OK) {
        pd_particles_free(p);
        return s;
    }
    *pout = p;
    *w = (pd_body_read){1, first_bond, 0, (*bout)->count};
    return PD_OK;
}

/* Every frame of the run laid out (pd_frame_steps: the steps after `first`
 * that get one, and step 0 itself in a new run, `fresh`). */
static pd_status plan_frames(pd_file *out, int64_t n, int64_t nbonds,
                             const pd_scene *sc, unsigned fields, int64_t first, int fresh)
{
    const int64_t m = pd_frame_steps(sc, first, fresh, NULL);
    int64_t *steps = malloc((size_t)(m > 0 ? m : 1) * sizeof *steps);
    double *times = malloc((size_t)(m > 0 ? m : 1) * sizeof *times);
    if (steps == NULL || times == NULL) {
        free(steps);
        free(times);
        return pd_fail(PD_ERR_NOMEM, "out of memory planning %lld frames", (long long)m);
    }
    pd_frame_steps(sc, first, fresh, steps);
    for (int64_t k = 0; k < m; k++)
        times[k] = (double)steps[k] * sc->dt;
    pd_status s = pd_plan_frames(out, n, nbonds, m, steps, times, fields);
    free(steps);
    free(times);
    return s;
}

/* The last complete frame of a run: its name (of names, to free) and info. */
static pd_status last_frame(pd_file *f, int64_t *nframes, char ***names, pd_frame_info *fi)
{
    pd_status s = pd_list_frames(f, nframes, names);
    if (s == PD_OK && *nframes == 0)
        s = pd_fail(PD_ERR_FORMAT, "the run has no complete frame to restart from");
    if (s == PD_OK)
        s = pd_read_frame_info(f, (*names)[*nframes - 1], fi);
    return s;
}

/* The bond states of frame `name` (pd_run_file_load_state). */
static pd_status load_state(pd_file *f, const char *name, const pd_bonds *b,
                            const pd_body_read *w, uint64_t **bits)
{
    if ((*bits = calloc((size_t)pd_bits_words(b->count) + 1, 8)) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    return w && w->rows ? pd_read_frame_state_rows(f, name, w->first_bond, w->bonds, *bits,
                                                   w->bond_at)
                        : pd_read_frame_state(f, name, b->count, *bits);
}

/* The rows of frame `name` and of the restart slot of its step
 * (pd_run_file_load_rows). */
static pd_status load_rows(pd_file *f, const char *name, int64_t step, int64_t n, int64_t g0,
                           int64_t m, int64_t k0, int64_t nb, pd_restart *r, double *v[3])
{
    for (int d = 0; d < 3; d++)
        if ((v[d] = malloc((size_t)(m > 0 ? m : 1) * sizeof(double))) == NULL)
            return pd_fail(PD_ERR_NOMEM, "out of memory");
    pd_status s = pd_read_frame_vectors_rows(f, name, n, g0, m, NULL, v);
    return s == PD_OK ? pd_read_restart_rows(f, n, g0, m, step, k0, nb, r) : s;
}

pd_status pd_run_file_load_state(pd_file *f, const pd_bonds *b, const pd_body_read *w,
                                 int64_t *step, uint64_t **bits)
{
    int64_t nframes = 0;
    char **names = NULL;
    pd_frame_info fi;
    pd_status s = last_frame(f, &nframes, &names, &fi);
    if (s == PD_OK)
        s = load_state(f, names[nframes - 1], b, w, bits);
    if (s == PD_OK)
        *step = fi.step;
    pd_frames_free_list(nframes, names);
    return s;
}

pd_status pd_run_file_load_rows(pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t k0,
                                int64_t nb, pd_restart *r, double *v[3])
{
    int64_t nframes = 0;
    char **names = NULL;
    pd_frame_info fi;
    pd_status s = last_frame(f, &nframes, &names, &fi);
    if (s == PD_OK)
        s = load_rows(f, names[nframes - 1], fi.step, n, g0, m, k0, nb, r, v);
    pd_frames_free_list(nframes, names);
    return s;
}

pd_status pd_run_file_load(pd_file *f, const pd_particles *p, const pd_bonds *b, int64_t *step,
                           pd_restart *r, double *v[3], uint64_t **bits)
{
    int64_t nframes = 0; /* the frames listed once */
    char **names = NULL;
    pd_frame_info fi;
    pd_status s = last_frame(f, &nframes, &names, &fi);
    if (s == PD_OK)
        s = load_state(f, names[nframes - 1], b, NULL, bits);
    if (s == PD_OK)
        s = load_rows(f, names[nframes - 1], fi.step, p->n, 0, p->n, 0, -1, r, v);
    if (s == PD_OK)
        *step = fi.step;
    pd_frames_free_list(nframes, names);
    return s;
}

pd_status pd_write_model(pd_file *out, const pd_file *from, const char *cmdline,
                         const pd_particles *p, const pd_bonds *b, const pd_sets *sets)
{
    pd_status s = pd_write_header(out, from, cmdline);
    if (s == PD_OK)
        s = pd_write_particles(out, p);
    if (s == PD_OK && b)
        s = pd_write_bonds(out, b);
    if (s == PD_OK)
        s = pd_write_sets(out, sets);
    return s;
}

/* pd_run_file_start, and on MPI ranks whose b holds their own rows alone
 * its part (NULL: b is the whole body's). */
static pd_status run_file_start(pd_file *out, int restart, const pd_file *from,
                                const pd_particles *p, const pd_bonds *b, const pd_part *part,
                                const pd_sets *sets, const pd_scene *sc, const char *effects,
                                const char *cmdline, const char *text, int64_t first)
{
    pd_status s;
    const int64_t nbonds = part ? part->nbonds : b->count, n = part ? part->n : p->n;
    if (restart) {
        /* the same file goes on: unfinished frames out, the scene and the
         * history say what was added */
        s = pd_drop_incomplete_frames(out);
        if (s == PD_OK)
            s = pd_append_history(out, cmdline);
    } else if (part) { /* the model, each rank its part's bonds */
        s = pd_write_header(out, from, cmdline);
        if (s == PD_OK)
            s = pd_write_particles_part(out, part, p);
        if (s == PD_OK)
            s = pd_write_bonds_part(out, part, b);
        if (s == PD_OK)
            s = pd_write_sets(out, sets);
    } else
        s = pd_write_model(out, from, cmdline, p, b, sets);
    if (s == PD_OK)
        s = pd_write_scene(out, sc, effects, text);
    /* every frame laid out now, then the file under its final name: a run
     * killed at any moment leaves it readable with its complete frames */
    if (s == PD_OK)
        s = plan_frames(out, n, nbonds, sc,
                        sc->fields | (sc->has_projectile ? PD_FRAME_PROJECTILE : 0) |
                            (sc->damping > 0 && !sc->relax ? PD_FRAME_DAMPING : 0),
                        first, !restart);
    if (s == PD_OK) /* the time series' rows too */
        s = pd_plan_series(out, sc, first, !restart);
    /* two restart slots, so that a kill while one is written leaves the
     * other, of the last complete frame; a fresh run of one frame needs
     * one (a kill before it is complete leaves no frame to go on from) */
    const int slots = restart || pd_frame_steps(sc, first, !restart, NULL) > 1 ? 2 : 1;
    if (s == PD_OK)
        s = pd_plan_restart(out, n, sc->has_failure, sc->has_contact, slots);
    if (s == PD_OK && sc->has_projectile)
        s = pd_plan_restart_projectile(out);
    if (s == PD_OK && sc->damping > 0 && !sc->relax)
        s = pd_plan_restart_damping(out);
    const int width = pd_model_history_width(pd_model_of(sc->model));
    if (s == PD_OK && width > 0 && nbonds > 0)
        s = pd_plan_restart_history(out, nbonds, width);
    if (s == PD_OK)
        s = pd_file_publish(out);
    return s;
}

pd_status pd_run_file_start(pd_file *out, int restart, const pd_file *from,
                            const pd_particles *p, const pd_bonds *b, const pd_sets *sets,
                            const pd_scene *sc, const char *effects, const char *cmdline,
                            const char *text, int64_t first)
{
    return run_file_start(out, restart, from, p, b, NULL, sets, sc, effects, cmdline, text,
                          first);
}

pd_status pd_run_file_start_part(pd_file *out, int restart, const pd_file *from,
                                 const pd_particles *p, const pd_bonds *b, const pd_part *part,
                                 const pd_sets *sets, const pd_scene *sc, const char *effects,
                                 const char *cmdline, const char *text, int64_t first)
{
    return run_file_start(out, restart, from, p, b, part, sets, sc, effects, cmdline, text,
                          first);
}

pd_status pd_run_file_frame(pd_file *out, const pd_sim *sim, unsigned fields, pd_energy *energy)
{
    /* the run's own particles and bonds (a piece's on MPI ranks); on MPI ranks every rank takes part in each sum and write below */
    pd_part pt;
    pd_sim_part(sim, &pt);
    pd_frame_info fi = {.step = pd_sim_stepno(sim), .time = pd_sim_time(sim),
                        .broken = pd_sim_broken(sim), .lost = pd_sim_lost(sim)};
    fi.has_projectile = pd_sim_projectile(sim, fi.projectile_position, fi.projectile_velocity);
    fi.has_damping = pd_sim_damping(sim) > 0;
    const pd_particles *q = pd_sim_particles(sim);
    size_t n = (size_t)(q->n > 0 ? q->n : 1);
    double *density = NULL, *stress = NULL, *mises = NULL, *damage = malloc(n * sizeof(double));
    pd_status s = damage ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory for the damage");
    if (s == PD_OK && (fields & PD_FIELD_ENERGY) &&
        (density = malloc(n * sizeof(double))) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the strain energy density");
    if (s == PD_OK && (fields & PD_FIELD_STRESS) &&
        ((stress = malloc(9 * n * sizeof(double))) == NULL ||
         (mises = malloc(n * sizeof(double))) == NULL))
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the stress");
    if (out->ranks > 1)
        s = pd_comm_agree(s);
    if (s == PD_OK)
        s = pd_sim_energy(sim, &fi.energy, density);
    /* the frame's damage from its bond states, as pd-damage computes it */
    const uint64_t *intact = pd_sim_intact(sim);
    if (s == PD_OK)
        pd_sim_damage(sim, damage);
    if (s == PD_OK) /* the series' row of the step before the frame (a
                       restart from the frame finds it), with its damage */
        s = pd_run_file_sample_damage(out, sim, &fi.energy, damage);
    if (s == PD_OK && stress) {
        s = pd_sim_stress(sim, stress);
        for (int64_t i = pt.lo; i < pt.lo + pt.rows; i++)
            mises[i] = pd_von_mises(stress + 9 * i);
    }
    pd_frame_fields ff = {damage, density, stress, mises};
    /* what a restart needs, then the frame (marked complete last) */
    pd_restart r;
    memset(&r, 0, sizeof r);
    pd_sim_accumulated(sim, &r);
    if (s == PD_OK)
        s = pd_write_restart_part(out, &pt, fi.step, &r);
    if (s == PD_OK)
        s = pd_write_frame_part(out, &pt, &fi, q->x, pd_sim_positions(sim),
                                pd_sim_velocities(sim), intact, &ff);
    free(damage);
    free(density);
    free(stress);
    free(mises);
    if (energy)
        *energy = fi.energy;
    return s;
}

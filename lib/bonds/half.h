/*
 * half.h -- internal (lib/bonds/half.c): the bonds of a run, each stored
 * once (i < j).
 */
#ifndef PD_HALF_H
#define PD_HALF_H

#include "pd.h"

/* The PMB bond list in lanes (lib/models/pmb_lanes.c): each block's rows
 * in groups of 8, one row a lane of a vector, and each group's columns,
 * a half bond of each lane a column (row i's k-th half bond in its k-th
 * column, partners ascending).  Within windows of PMB_LANES_WINDOW rows
 * of a block, the rows with more half bonds come first, so that a group's
 * lanes have about as many. */
typedef struct {
    int64_t groups;
    int64_t *first;   /* nblocks + 1: each block's first group            */
    int64_t *col;     /* groups + 1: each group's first column            */
    int64_t *row;     /* 8 per group: each lane's row, or -1 (no row)     */
    uint32_t *at;     /* 8 per column: the partner j's place 8 j in
                         h->pack (a lane without a bond there: its own
                         row's, or the group's first row's)               */
    double *length;   /* 8 per column: |xi|, m (1 where no bond)          */
    double *w, *wji;  /* 8 per column: w_ij and w_ji of the half bond (0
                         where none); wji NULL when they are the same     */
    double *kfail;    /* 8 per column with per-bond laws, else NULL       */
    uint8_t *act;     /* per column: the lanes with a bond there          */
    uint8_t *bits;    /* per column: the lanes whose bond is intact, as
                         the half bonds' bits say at `epoch`              */
    uint64_t epoch;
} pd_half_lanes;

/* The bonds of a run, each stored once (i < j), as the PMB kernel walks
 * them; the directed bonds of the file are expanded from it on demand. */
typedef struct {
    int64_t n;         /* particles                                      */
    int64_t count;     /* bonds                                          */
    int64_t *offset;   /* n+1 CSR offsets                                */
    int32_t *neighbor; /* j > i, ascending                               */
    double *length;    /* |xi|, m                                        */
    double *w_ij;      /* c V_j nu_ij: force density on i per stretch    */
    double *w_ji;      /* c V_i nu_ji: force density on j per stretch
                          (the same array as w_ij when they are equal)   */
    uint64_t *intact;  /* mu per bond                                    */
    int64_t block;     /* rows per block (>= the largest j - i)          */
    int64_t nblocks;
    int64_t walk;      /* blocks the bond list's kernel walks: nblocks, or
                          (a piece of a body on MPI ranks) up to its own
                          last                                           */
    int64_t walk_lo;   /* the first block it walks: 0, or (a piece) the
                          block below its own; the blocks below that put
                          no force on its rows                           */
    int64_t blk0;      /* the whole body's block of block 0 (a piece): a
                          phase walks the blocks of its parity in the
                          whole body                                     */
    int64_t clip;      /* 0, or (that piece, when walk_lo is not its own)
                          its first own row: block walk_lo is walked from
                          its first row with a partner at or above it    */
    double *released;  /* nblocks: energy of the bonds broken in a block
                          in this step, J (summed in block order)        */
    int64_t *cursor;   /* scratch of the weights' set-up (pmb.c, lps.c)    */
    double *kfail;     /* per bond s00_bond / s00: the bond breaks at
                          kfail min(s0_i, s0_j) (lib/models/materials.c); NULL:
                          all 1, the kernel of old                       */
    uint64_t epoch;    /* bumped when `intact` is changed from outside the
                          kernels (a restart, a lost particle)           */
    double *pack;      /* n x 8, 64-byte aligned, or NULL: the AVX-512
                          rows' own copy of each particle's position (m)
                          and s0 (4 doubles), then its force density
                          (N/m^3) and new s0 (4), one cache line a
                          particle (lib/models/pmb.c)                    */
    int contact;       /* the AVX-512 rows take the contact of the pairs of
                          the half bonds, intact or not: the contact list
                          holds only the other pairs (lib/effects/contact.c) */
    double gap;        /* with `contact`: no pair that is not a half bond
                          is closer than this in the reference
                          configuration, m                               */
    double contact_cap;/* with `contact`: 1.35 (r_i + r_j) when every node
                          radius is the same, else +inf, m               */
    double *eb, *ec;   /* n each, or NULL (the AVX-512 rows): each
                          particle's elastic and contact energy, J, as a
                          bond pass counted them (lib/models/pmb_rows.c) */
    int energy_ok;     /* they are those of step energy_step, with the
                          bits at energy_epoch                           */
    int64_t energy_step;
    uint64_t energy_epoch;
    pd_half_lanes *lanes; /* NULL, or the bond list in lanes (the AVX-512
                             rows' faster walk, lib/models/pmb_lanes.c),
                             which then hold the lengths and weights:
                             length, w_ij and w_ji are NULL              */
} pd_half_bonds;
/* Free the lanes of h (NULL after). */
void pd_half_lanes_free(pd_half_bonds *h);
/* The half bonds of b: rows, partners and state (what every kernel needs);
 * lib/models/pmb_rows.c's pd_half_weights adds the lengths and the weights
 * c V nu that its bond list walks. */
pd_status pd_half_build(const pd_bonds *b, pd_half_bonds *h);
/* The largest span j - i of a bond of b (at least 1), and the rows of
 * pd_half_build's blocks for n rows of that span (*nblocks of them): what
 * the half bonds of b would be cut into, without building them. */
int64_t pd_half_span(const pd_bonds *b);
int64_t pd_half_block_of(int64_t n, int64_t span, int64_t *nblocks);
void pd_half_free(pd_half_bonds *h);
/* Blocks of `block` rows (a piece of a body cut as the whole body is,
 * lib/run/piece.c), in place of pd_half_build's own: at least every
 * bond's span j - i. */
pd_status pd_half_set_block(pd_half_bonds *h, int64_t block);
/* The half bonds' bits from directed state bits (the file's), and back. */
void pd_half_set_state(pd_half_bonds *h, const pd_bonds *b, const uint64_t *intact);
void pd_half_expand(const pd_half_bonds *h, const pd_bonds *b, uint64_t *intact);
/* pd_damage of the half bonds' own bits, bit for bit, without expanding
 * them into directed bits: where every volume is equal (a sum of m volumes
 * is then the m-th running sum, as pd_damage counts), the intact bonds of
 * each particle counted over the half bonds.  1 done; 0 (unequal volumes,
 * a piece of a body, no lists, out of memory): pd_damage is the way. */
int pd_half_damage(const pd_particles *p, const pd_bonds *b, const pd_half_bonds *h,
                   double *damage);
/* Break every bond of particle i (both halves). */
void pd_half_break_all(pd_half_bonds *h, const pd_bonds *b, int64_t i);
/* The half bond i-j (i < j): its index, or -1 when there is none. */
int64_t pd_half_find(const pd_half_bonds *h, int64_t i, int64_t j);
/* The smallest reference distance between two particles that are not a
 * half bond, or the horizon of b when no such pair is closer (a cell
 * search of that radius over p's positions: when b's families are those
 * pd-bonds makes, every pair within the horizon, as many as a count
 * finds, the horizon at once; else pair by pair). */
pd_status pd_half_gap(const pd_half_bonds *h, const pd_bonds *b, const pd_particles *p,
                      double *gap);
/* The same over the pairs of rows [lo, hi) (each pair from its lower end,
 * within b's families of those rows, which must be whole); with `ranks`,
 * the rows of a piece of the body on MPI ranks, whose owned rows together
 * are the body: the whole body's answer on every rank (collective). */
pd_status pd_half_gap_rows(const pd_half_bonds *h, const pd_bonds *b, const pd_particles *p,
                           int64_t lo, int64_t hi, int ranks, double *gap);

#endif

/*
 * pd-run -- integrate the peridynamic equation of motion for the effects a
 * scene declares.
 *
 * Velocity Verlet (seed 000 Algorithm 1) over the PMB bond force (seed 000
 * eqs. 5-7), with, only when declared: bond failure by critical stretch
 * (eqs. 8-9), short-range contact (eqs. 13-15) and a moving spherical
 * indenter (LAMMPS fix indent), a projectile the body pushes back
 * (lib/effects/projectile.c, seed 004 section 6), and boundary conditions on the
 * particle sets of pd-lattice --set (seed 004 §2: body forces and
 * prescribed velocity or displacement in a layer).  The time step defaults to the stable step
 * of seed 004 eq. 46 times a safety factor; a larger --dt is refused.
 * Writes the model, the resolved scene (/scene) and frames (/frames).
 * A 2-D plate (/particles dimension 2) takes the plane-stress constants of
 * lib/models/plate.c: its --bulk-modulus is the 2-D bulk modulus.
 * --material, --interface and --fibre give bonds their own PMB constants
 * (lib/models/materials.c, seed 004 eq. 10).
 */
#include <getopt.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "pd.h"

#define PROG "pd-run"
#include "cli.h"
#define MAX_BC 64

struct options {
    pd_scene_spec spec; /* the scene as given (lib/run/scene.c)      */
    int has_steps, has_status, has_output;
    int64_t status_every;
    int64_t series_every; /* --series N; 0: the status interval */
    const char *input;
    const char *output;
    const char *restart; /* --restart RUN.h5: go on from its last frame */
    int quiet, timing, debug;
    int strict;          /* --strict: a warning about the scene is an error */
    pd_bc bc[MAX_BC]; /* --velocity-bc, --displacement-bc, --body-force */
    int nbc;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... (--steps N | --time T) INPUT [-o FILE]\n"
            "  or:  " PROG " --restart RUN.h5 --steps N [--every N] [-o FILE]\n"
            "Integrate a peridynamic model (pd-h5 with /bonds); INPUT '-' is stdin.\n"
            "\n"
            "Model:\n"
            "  --model pmb|lps|ves|eps\n"
            "                        prototype microelastic brittle (default), linear\n"
            "                        peridynamic solid, or its viscoelastic or\n"
            "                        elastic-plastic variant\n"
            "  --c C                 micromodulus, N/m^6 (pmb)\n"
            "  --bulk-modulus K      bulk modulus, Pa (c = 18K/(pi delta^4));\n"
            "                        the last of --c, --bulk-modulus and\n"
            "                        --youngs-modulus wins; for a 2-D plate K is the\n"
            "                        plane-stress bulk modulus and c = 12K/(pi H delta^3)\n"
            "  --youngs-modulus E    Young's modulus, Pa (pmb): K = 2E/3 in 3-D (PMB has\n"
            "                        nu = 1/4), K = 3E/4 for a 2-D plate (plane stress,\n"
            "                        nu = 1/3: c = 9E/(pi H delta^3))\n"
            "  --shear-modulus G     shear modulus, Pa (lps, required there)\n"
            "  --influence W         influence function of lps: 1/r (default), 1 or\n"
            "                        gaussian (exp(-|xi|^2/delta^2)); lps is 3-D only\n"
            "  --ellipsoid UX,UY,UZ,A,B,ROLL\n"
            "                        anisotropic influence (lps; up to 8, the largest\n"
            "                        wins): omega times the distance to an ellipsoid\n"
            "                        with semi-axes 1, A, B (A, B in (0,1]) along U and\n"
            "                        two normals rolled ROLL radians about U (seed 002)\n"
            "  --ves-lambda L        ves: the viscous fraction lambda of the deviatoric\n"
            "                        part, 0 <= L <= 1 (LAMMPS peri/ves m_lambdai)\n"
            "  --ves-tau T           ves: the relaxation time tau, s (m_taubi)\n"
            "                        (ves takes --bulk-modulus, --shear-modulus and\n"
            "                        --influence as lps, and both of these)\n"
            "  --yield-stress Y      eps: the yield stress, Pa (and K, G, --influence as\n"
            "                        lps)\n"
            "Effects (each only when given):\n"
            "  --failure S00,ALPHA   critical stretch s0 = S00 - ALPHA s_min (both\n"
            "                        dimensionless)\n"
            "  --failure-energy G0[,ALPHA]\n"
            "                        the same with S00 from the fracture energy G0 (J/m^2):\n"
            "                        sqrt(10 G0/(pi c delta^5)) = sqrt(5 G0/(9 K delta))\n"
            "                        (seed 004 eq. 27; pmb only); for a 2-D plate\n"
            "                        sqrt(4 G0/(c H delta^4)) = sqrt(4 pi G0/(9 E delta));\n"
            "                        ALPHA defaults to 0\n"
            "  --contact             short-range contact forces\n"
            "  --contact-skin S      skin of the contact list, m (default (gap - reach)/2,\n"
            "                        0.5 to 1 spacing: 0.906 spacings at delta = 3 spacings)\n"
            "  --indenter sphere,X,Y,Z,R,K,VX,VY,VZ\n"
            "                        moving spherical indenter: centre X,Y,Z (m) at t = 0,\n"
            "                        radius R (m), force density K (R-r)^2 with K in\n"
            "                        N/m^5, velocity VX,VY,VZ (m/s)\n"
            "  --velocity-bc SET,AXIS,PROFILE\n"
            "                        hold the AXIS (x|y|z) motion of the particles of SET\n"
            "                        (pd-lattice --set): velocity PROFILE(t), m/s, and\n"
            "                        position x + its integral; repeatable\n"
            "  --displacement-bc SET,AXIS,PROFILE\n"
            "                        hold the AXIS displacement at PROFILE(t), m\n"
            "  --body-force SET,AXIS,PROFILE\n"
            "                        add the force density PROFILE(t), N/m^3, along AXIS\n"
            "                        PROFILE: a number; points:T0,V0,T1,V1,... (piecewise\n"
            "                        linear); table:FILE ('time value' lines); or\n"
            "                        pulses:V1,D1,V2,D2,... (V1 for D1 s from t = 0, ...)\n"
            "  --damping C[,SET]     viscous damping, the force density -C rho v (C in 1/s)\n"
            "                        on every particle or on those of SET; the energy it\n"
            "                        takes is booked as damped=\n"
            "  --no-failure SET      a bond with an end in SET never breaks (grips, loaded\n"
            "                        edges: fracture starts where the physics puts it);\n"
            "                        repeatable; needs --failure\n"
            "  --relax               quasi-static: each step a load step, the loads of time\n"
            "                        n dt (--dt required), relaxed by adaptive dynamic\n"
            "                        relaxation (with --damping C: that damping instead)\n"
            "  --relax-tolerance F   a load step is relaxed when the residual force is F\n"
            "                        times the load (default 1e-4)\n"
            "  --relax-iterations N  at most N iterations per load step (default 1000000)\n"
            "  --projectile sphere,X,Y,Z,R,MASS,VX,VY,VZ[,K]\n"
            "                        rigid sphere the body pushes back: centre X,Y,Z (m)\n"
            "                        at t = 0, radius R (m), mass MASS (kg), velocity\n"
            "                        VX,VY,VZ (m/s); the indenter's force law, K in N/m^5\n"
            "                        (default: from the bond stiffness, see pd-run(1))\n"
            "Materials and fibres (pmb; see pd-run(1)):\n"
            "  --material ID,c=C|K=K[,s00=S]\n"
            "                        the bonds inside material ID (pd-lattice --material)\n"
            "                        take micromodulus C (N/m^6) or bulk modulus K (Pa)\n"
            "                        and critical stretch S00 (needs --failure)\n"
            "  --interface A,B,c=C|K=K[,s00=S]\n"
            "                        the same for the bonds between materials A and B;\n"
            "                        without it: the harmonic mean of the two c, the\n"
            "                        smaller s00\n"
            "  --fibre GX,GY,GZ,C_FIBRE,C_MATRIX[,S_FIBRE,S_MATRIX]\n"
            "                        fibres along g (seed 004 eq. 10): a bond at angle\n"
            "                        beta = g.xi/|g||xi| takes c = beta^2 C_FIBRE +\n"
            "                        (1 - beta^2) C_MATRIX and s00 likewise; for the\n"
            "                        materials without --material\n"
            "Time:\n"
            "  --steps N             number of steps\n"
            "  --time T              or: run to time T, s, in the fewest equal steps of\n"
            "                        at most the time step (the later of --steps and\n"
            "                        --time wins)\n"
            "  --dt DT               time step, s (default: stable step x safety)\n"
            "  --safety F            safety factor on the stable step (default 0.8)\n"
            "  --force-dt            run a --dt above the stable step anyway\n"
            "  --lost-margin D       a particle farther than D (m) outside the body's\n"
            "                        bounding box is lost: its bonds break and it stays\n"
            "                        at rest (default 10 x the box's largest edge)\n"
            "  --every N             a frame every N steps; 0 = only the last (default 0)\n"
            "Output:\n"
            "  --series N            a row of the time series (/series: energies, damage,\n"
            "                        each set's displacement and reaction force, the\n"
            "                        projectile's and indenter's motion and force; read\n"
            "                        with pd-series) every N steps and at the last\n"
            "                        (default: the status interval)\n"
            "  --fields LIST         optional per-particle fields of each frame, a comma\n"
            "                        list of: energy (strain_energy_density, J/m^3),\n"
            "                        stress (the peridynamic stress tensor and its von\n"
            "                        Mises value, Pa)\n"
            "Other:\n"
            "  --restart RUN.h5      go on from the last complete frame of RUN.h5 for N\n"
            "                        more steps, with its scene (only --steps, --every,\n"
            "                        --series, --threads, --status, --timing, --strict,\n"
            "                        --balance-limit, -q, -o may be given);\n"
            "                        RUN.h5 is updated unless -o names another file\n"
            "  --scene FILE          read options from FILE ('option value' lines);\n"
            "                        the command line overrides it\n"
            "  --threads N           OpenMP threads (default: all cores)\n"
            "  --allow-overlap       let a projectile or indenter start inside the body\n"
            "                        (else an error naming the depth and the particle)\n"
            "  --balance-limit F     stop (exit 1, the frames before kept) when the energy\n"
            "                        balance drifts from step 0 by more than F times the\n"
            "                        energy put in; 'off': never (default 1)\n"
            "  --strict              a warning about the scene (a value no solid has, a\n"
            "                        run that ends before first contact, ...) is an\n"
            "                        error\n"
            "  --bond-list           walk the bonds (pmb, lps) as a list even when the\n"
            "                        body is on a lattice (the lattice stencil kernel\n"
            "                        is the default there; the two agree to rounding)\n"
            "  --status N            a status line every N steps (default steps/10)\n"
            "  --timing              print where the time went\n"
            "  -o, --output FILE     output file, '-' for stdout (default '-')\n"
            "  -q, --quiet           no log on stderr\n"
            "      --debug           print HDF5's own error stack\n"
            "  -h, --help            show this help\n"
            "  -V, --version         show the version\n");
}

static int positive(const char *opt, const char *arg, double *out)
{
    if (!pd_parse_double(arg, out) || !(*out > 0)) {
        char msg[128];
        snprintf(msg, sizeof msg, "%s must be a positive number, not", opt);
        return usage_error(msg, arg);
    }
    return 0;
}

/* --velocity-bc, --displacement-bc, --body-force SET,AXIS,PROFILE. */
static int parse_bc(struct options *o, pd_bc_kind kind, const char *arg)
{
    if (o->nbc == MAX_BC)
        return usage_error("too many boundary conditions", NULL);
    pd_status s = pd_bc_parse(kind, arg, &o->bc[o->nbc]);
    if (s == PD_ERR_IO || s == PD_ERR_NOMEM)
        return fail(); /* an unreadable table: a runtime error */
    if (s != PD_OK)
        return usage_error(pd_errmsg(), NULL);
    o->nbc++;
    return 0;
}

static void free_bc(struct options *o)
{
    for (int k = 0; k < o->nbc; k++)
        pd_profile_free(&o->bc[k].profile);
    o->nbc = 0;
}

/* --material ID,c=C|K=K[,s00=S] and --interface A,B,...: a bond law.  A pair
 * given again replaces the earlier law (the command line overrides the
 * scene file). */
static int parse_law(struct options *o, int interface, const char *arg)
{
    const char *what = interface ? "--interface needs A,B,c=C|K=K[,s00=S] (A != B), not"
                                 : "--material needs ID,c=C|K=K[,s00=S], not";
    pd_bond_law law = {0};
    double k = 0;
    int have_c = 0, nid = 0;
    char buf[512];
    if (strlen(arg) >= sizeof buf)
        return usage_error(what, arg);
    strcpy(buf, arg);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        int64_t id;
        double v;
        if (nid < 1 + interface) {
            if (!pd_parse_int64(tok, &id) || id < 0 || id > INT32_MAX)
                return usage_error(what, arg);
            if (nid++ == 0)
                law.a = law.b = (int32_t)id;
            else
                law.b = (int32_t)id;
        } else if (strncmp(tok, "c=", 2) == 0 && pd_parse_double(tok + 2, &v) && v > 0 &&
                   isfinite(v))
            law.c = v, k = 0, have_c = 1;
        else if (strncmp(tok, "K=", 2) == 0 && pd_parse_double(tok + 2, &v) && v > 0 &&
                 isfinite(v))
            k = v, law.c = 0, have_c = 1;
        else if (strncmp(tok, "s00=", 4) == 0 && pd_parse_double(tok + 4, &v) && v > 0 &&
                 isfinite(v))
            law.s00 = v;
        else
            return usage_error(what, arg);
    }
    if (nid < 1 + interface || !have_c || (interface && law.a == law.b))
        return usage_error(what, arg);
    int slot = 0;
    while (slot < o->spec.nlaws && !((o->spec.laws[slot].a == law.a && o->spec.laws[slot].b == law.b) ||
                                (o->spec.laws[slot].a == law.b && o->spec.laws[slot].b == law.a)))
        slot++;
    if (slot == PD_LAWS_MAX)
        return usage_error("too many --material and --interface laws", NULL);
    o->spec.laws[slot] = law;
    o->spec.law_k[slot] = k;
    o->spec.nlaws += slot == o->spec.nlaws;
    if (interface)
        o->spec.has_interface = 1;
    else
        o->spec.has_material = 1;
    return 0;
}

/* --fibre GX,GY,GZ,C_FIBRE,C_MATRIX[,S_FIBRE,S_MATRIX]. */
static int parse_fibre(pd_scene *sc, const char *arg)
{
    double v[7] = {0};
    int seven = pd_parse_doubles(arg, v, 7);
    if ((!seven && !pd_parse_doubles(arg, v, 5)) || !(v[3] > 0) || !(v[4] > 0) ||
        (seven && (!(v[5] > 0) || !(v[6] > 0))) || !isfinite(v[3]) || !isfinite(v[4]) ||
        !(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > 0) ||
        !isfinite(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
        return usage_error("--fibre needs GX,GY,GZ,C_FIBRE,C_MATRIX[,S_FIBRE,S_MATRIX] with g "
                           "not zero and positive C and S, not",
                           arg);
    sc->has_fibre = 1;
    for (int d = 0; d < 3; d++)
        sc->fibre_g[d] = v[d];
    for (int e = 0; e < 2; e++) {
        sc->fibre_c[e] = v[3 + e];
        sc->fibre_s00[e] = v[5 + e];
    }
    return 0;
}

/* --fields LIST: the optional per-particle fields of the frames. */
static int parse_fields(const char *arg, unsigned *fields)
{
    static const struct { const char *name; unsigned bit; } known[] = {
        {"energy", PD_FIELD_ENERGY}, {"stress", PD_FIELD_STRESS}};
    *fields = 0;
    const char *p = arg;
    while (*p) {
        size_t len = strcspn(p, ",");
        unsigned bit = 0;
        for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
            if (strlen(known[k].name) == len && strncmp(p, known[k].name, len) == 0)
                bit = known[k].bit;
        if (bit == 0)
            return usage_error("--fields takes a comma list of: energy, stress; not", arg);
        *fields |= bit;
        p += len + (p[len] == ',');
    }
    return 0;
}

/* The strings read from the scene file, freed at exit. */
static char **scene_strings;
static int scene_count;
static int *scene_lines;

static void free_scene_strings(void)
{
    for (int k = 0; k < scene_count; k++)
        free(scene_strings[k]);
    free(scene_strings);
    free(scene_lines);
}

/* argv with the scene file's options first, then the command line's (so the
 * command line wins); the --scene option itself is dropped. */
/* May a --restart command line give this option?  Only what changes
 * neither the physics nor the steps already taken. */
static int restart_safe(const char *arg)
{
    static const char *safe[] = {"--restart", "--steps",  "--every",         "--threads",
                                 "--status",  "--series", "--timing",        "-q",
                                 "--quiet",   "-o",       "--output",        "--debug",
                                 "--strict",  "--balance-limit", NULL};
    for (int k = 0; safe[k]; k++) {
        size_t len = strlen(safe[k]);
        if (strncmp(arg, safe[k], len) == 0 && (arg[len] == '\0' || arg[len] == '='))
            return 1;
    }
    return strncmp(arg, "-o", 2) == 0; /* -oFILE */
}

static int expand_scene(int argc, char **argv, int *nargc, char ***nargv)
{
    const char *scene = NULL, *restart = NULL;
    for (int k = 1; k < argc; k++) {
        if (strcmp(argv[k], "--") == 0)
            break;
        if (strcmp(argv[k], "--scene") == 0) {
            if (k + 1 >= argc)
                return usage_error("--scene needs a FILE", NULL);
            scene = argv[k + 1];
        } else if (strncmp(argv[k], "--scene=", 8) == 0)
            scene = argv[k] + 8;
        else if (strcmp(argv[k], "--restart") == 0 && k + 1 < argc)
            restart = argv[k + 1];
        else if (strncmp(argv[k], "--restart=", 10) == 0)
            restart = argv[k] + 10;
    }
    char *text = NULL;
    if (restart) {
        /* the scene goes on: the run's own options first, and only safe
         * ones from the command line */
        for (int k = 1; k < argc; k++)
            if (argv[k][0] == '-' && argv[k][1] != '\0' && !restart_safe(argv[k]))
                return usage_error("--restart goes on with the scene of the run; this option "
                                   "would change it:",
                                   argv[k]);
            else if (argv[k][0] == '-' && (strcmp(argv[k], "--restart") == 0 ||
                                            strcmp(argv[k], "--steps") == 0 ||
                                            strcmp(argv[k], "--every") == 0 ||
                                            strcmp(argv[k], "--threads") == 0 ||
                                            strcmp(argv[k], "--status") == 0 ||
                                            strcmp(argv[k], "-o") == 0 ||
                                            strcmp(argv[k], "--output") == 0))
                k++; /* its value */
        pd_file *f = NULL;
        pd_status st = pd_file_open(restart, &f);
        if (st == PD_OK)
            st = pd_read_scene_options(f, &text);
        pd_file_close(f);
        if (st != PD_OK)
            return fail();
    }
    int sc = 0;
    char **sv = NULL;
    pd_status st = PD_OK;
    if (text)
        st = pd_scene_args_text(text, restart, &sc, &sv, &scene_lines);
    else if (scene)
        st = pd_scene_args(scene, &sc, &sv, &scene_lines);
    free(text);
    if (st != PD_OK)
        return fail();
    scene_strings = sv;
    scene_count = sc;
    atexit(free_scene_strings);
    cli_scene.file = restart ? restart : scene; /* its errors name FILE:LINE */
    cli_scene.args = sv;
    cli_scene.line = scene_lines;
    cli_scene.count = sc;
    char **v = malloc((size_t)(argc + sc + 1) * sizeof *v);
    if (v == NULL)
        return 1;
    int n = 0;
    v[n++] = argv[0];
    for (int k = 0; k < sc; k++)
        v[n++] = sv[k];
    for (int k = 1; k < argc; k++) {
        if (strcmp(argv[k], "--scene") == 0) {
            k++;
            continue;
        }
        if (strncmp(argv[k], "--scene=", 8) == 0)
            continue;
        v[n++] = argv[k];
    }
    v[n] = NULL;
    *nargc = n;
    *nargv = v;
    return 0;
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_MODEL = 256, OPT_C, OPT_K, OPT_FAILURE, OPT_CONTACT, OPT_SKIN, OPT_INDENTER,
           OPT_STEPS, OPT_DT, OPT_SAFETY, OPT_FORCE_DT, OPT_EVERY, OPT_THREADS, OPT_STATUS,
           OPT_TIMING, OPT_RESTART, OPT_FIELDS, OPT_LOST, OPT_G0, OPT_E, OPT_VBC, OPT_DBC,
           OPT_BODY, OPT_G, OPT_INFLUENCE, OPT_PROJECTILE, OPT_ELLIPSOID, OPT_MATERIAL,
           OPT_INTERFACE, OPT_FIBRE, OPT_LAMBDA, OPT_TAU, OPT_YIELD, OPT_BONDLIST,
           OPT_OVERLAP, OPT_STRICT, OPT_BALANCE, OPT_DAMPING, OPT_NO_FAILURE, OPT_SERIES,
           OPT_RELAX, OPT_RELAX_TOL, OPT_RELAX_IT, OPT_TIME };
    static const struct option longopts[] = {
        {"model", required_argument, 0, OPT_MODEL},
        {"c", required_argument, 0, OPT_C},
        {"bulk-modulus", required_argument, 0, OPT_K},
        {"youngs-modulus", required_argument, 0, OPT_E},
        {"shear-modulus", required_argument, 0, OPT_G},
        {"influence", required_argument, 0, OPT_INFLUENCE},
        {"failure", required_argument, 0, OPT_FAILURE},
        {"failure-energy", required_argument, 0, OPT_G0},
        {"contact", no_argument, 0, OPT_CONTACT},
        {"contact-skin", required_argument, 0, OPT_SKIN},
        {"indenter", required_argument, 0, OPT_INDENTER},
        {"steps", required_argument, 0, OPT_STEPS},
        {"time", required_argument, 0, OPT_TIME},
        {"dt", required_argument, 0, OPT_DT},
        {"safety", required_argument, 0, OPT_SAFETY},
        {"force-dt", no_argument, 0, OPT_FORCE_DT},
        {"bond-list", no_argument, 0, OPT_BONDLIST},
        {"allow-overlap", no_argument, 0, OPT_OVERLAP},
        {"balance-limit", required_argument, 0, OPT_BALANCE},
        {"damping", required_argument, 0, OPT_DAMPING},
        {"no-failure", required_argument, 0, OPT_NO_FAILURE},
        {"strict", no_argument, 0, OPT_STRICT},
        {"every", required_argument, 0, OPT_EVERY},
        {"series", required_argument, 0, OPT_SERIES},
        {"relax", no_argument, 0, OPT_RELAX},
        {"relax-tolerance", required_argument, 0, OPT_RELAX_TOL},
        {"relax-iterations", required_argument, 0, OPT_RELAX_IT},
        {"threads", required_argument, 0, OPT_THREADS},
        {"status", required_argument, 0, OPT_STATUS},
        {"timing", no_argument, 0, OPT_TIMING},
        {"restart", required_argument, 0, OPT_RESTART},
        {"fields", required_argument, 0, OPT_FIELDS},
        {"lost-margin", required_argument, 0, OPT_LOST},
        {"velocity-bc", required_argument, 0, OPT_VBC},
        {"displacement-bc", required_argument, 0, OPT_DBC},
        {"body-force", required_argument, 0, OPT_BODY},
        {"projectile", required_argument, 0, OPT_PROJECTILE},
        {"ellipsoid", required_argument, 0, OPT_ELLIPSOID},
        {"material", required_argument, 0, OPT_MATERIAL},
        {"interface", required_argument, 0, OPT_INTERFACE},
        {"fibre", required_argument, 0, OPT_FIBRE},
        {"ves-lambda", required_argument, 0, OPT_LAMBDA},
        {"ves-tau", required_argument, 0, OPT_TAU},
        {"yield-stress", required_argument, 0, OPT_YIELD},
        {"output", required_argument, 0, 'o'},
        {"quiet", no_argument, 0, 'q'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->output = "-";
    o->spec.sc.model = PD_MODEL_PMB;
    o->spec.sc.safety = 0.8;
    int c, rc, status = 0;
    int64_t iv;
    double ind[8];
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case OPT_MODEL: {
            const pd_model *m = pd_model_by_name(optarg);
            if (m == NULL) {
                char known[128] = "unknown --model (this pd knows:";
                for (int k = 0; pd_model_at(k); k++)
                    snprintf(known + strlen(known), sizeof known - strlen(known), "%s %s",
                             k ? "," : "", pd_model_name(pd_model_at(k)));
                strcat(known, ")");
                return usage_error(known, optarg);
            }
            o->spec.sc.model = pd_model_kind_of(m);
            break;
        }
        case OPT_LAMBDA:
            if (!pd_parse_double(optarg, &o->spec.sc.ves_lambda) || !(o->spec.sc.ves_lambda >= 0) ||
                !(o->spec.sc.ves_lambda <= 1))
                return usage_error("--ves-lambda must be a number in [0, 1], not", optarg);
            o->spec.has_lambda = 1;
            break;
        case OPT_TAU:
            if ((rc = positive("--ves-tau", optarg, &o->spec.sc.ves_tau)))
                return rc;
            o->spec.has_tau = 1;
            break;
        case OPT_YIELD:
            if ((rc = positive("--yield-stress", optarg, &o->spec.sc.yield_stress)))
                return rc;
            o->spec.has_yield = 1;
            break;
        case OPT_G:
            if ((rc = positive("--shear-modulus", optarg, &o->spec.sc.shear_modulus)))
                return rc;
            o->spec.has_g = 1;
            break;
        case OPT_INFLUENCE: {
            int w = pd_influence_parse(optarg);
            if (w < 0)
                return usage_error("--influence takes 1/r, 1 or gaussian, not", optarg);
            o->spec.sc.influence = (pd_influence)w;
            o->spec.has_influence = 1;
            break;
        }
        case OPT_C:
            if ((rc = positive("--c", optarg, &o->spec.sc.c)))
                return rc;
            o->spec.has_c = 1; /* the last of --c, --bulk-modulus and --youngs-modulus wins */
            o->spec.has_k = 0;
            o->spec.has_e = 0;
            break;
        case OPT_K:
            if ((rc = positive("--bulk-modulus", optarg, &o->spec.sc.bulk_modulus)))
                return rc;
            o->spec.has_k = 1;
            o->spec.has_c = 0;
            o->spec.has_e = 0;
            o->spec.sc.youngs_modulus = 0;
            break;
        case OPT_E:
            if ((rc = positive("--youngs-modulus", optarg, &o->spec.sc.youngs_modulus)))
                return rc;
            o->spec.has_e = 1;
            o->spec.has_c = 0;
            o->spec.has_k = 0;
            break;
        case OPT_FAILURE: {
            double v[2];
            if (!pd_parse_doubles(optarg, v, 2) || !(v[0] > 0) || !(v[1] >= 0))
                return usage_error("--failure needs S00,ALPHA with S00 > 0 and ALPHA >= 0, not",
                                   optarg);
            o->spec.sc.has_failure = 1;
            o->spec.sc.s00 = v[0];
            o->spec.sc.alpha = v[1];
            o->spec.has_g0 = 0; /* the last of --failure and --failure-energy wins */
            break;
        }
        case OPT_G0: {
            double v[2] = {0, 0};
            if (!(pd_parse_doubles(optarg, v, 1) || pd_parse_doubles(optarg, v, 2)) ||
                !(v[0] > 0) || !(v[1] >= 0))
                return usage_error("--failure-energy needs G0[,ALPHA] with G0 > 0 (J/m^2) and "
                                   "ALPHA >= 0, not",
                                   optarg);
            o->spec.sc.has_failure = 1;
            o->spec.has_g0 = 1;
            o->spec.g0 = v[0];
            o->spec.sc.alpha = v[1];
            break;
        }
        case OPT_CONTACT:
            o->spec.sc.has_contact = 1;
            break;
        case OPT_SKIN:
            if ((rc = positive("--contact-skin", optarg, &o->spec.sc.contact_skin)))
                return rc;
            break;
        case OPT_INDENTER:
            if (strncmp(optarg, "sphere,", 7) != 0 || !pd_parse_doubles(optarg + 7, ind, 8))
                return usage_error("--indenter needs sphere,X,Y,Z,R,K,VX,VY,VZ, not", optarg);
            if (!(ind[3] > 0) || !(ind[4] > 0))
                return usage_error("--indenter radius R and stiffness K must be positive in",
                                   optarg);
            o->spec.sc.has_indenter = 1;
            for (int d = 0; d < 3; d++) {
                o->spec.sc.ind_center[d] = ind[d];
                o->spec.sc.ind_velocity[d] = ind[5 + d];
            }
            o->spec.sc.ind_radius = ind[3];
            o->spec.sc.ind_k = ind[4];
            break;
        case OPT_STEPS:
            if (!pd_parse_int64(optarg, &iv) || iv < 0)
                return usage_error("--steps must be a non-negative integer, not", optarg);
            o->spec.sc.steps = iv;
            o->has_steps = 1;
            o->spec.has_time = 0; /* the later of --steps and --time */
            break;
        case OPT_TIME:
            if ((rc = positive("--time", optarg, &o->spec.end_time)))
                return rc;
            o->spec.has_time = 1;
            o->has_steps = 0;
            break;
        case OPT_DT:
            if ((rc = positive("--dt", optarg, &o->spec.sc.dt)))
                return rc;
            o->spec.has_dt = 1;
            break;
        case OPT_SAFETY:
            if ((rc = positive("--safety", optarg, &o->spec.sc.safety)))
                return rc;
            if (o->spec.sc.safety > 1)
                return usage_error("--safety must not exceed 1, not", optarg);
            break;
        case OPT_BONDLIST:
            o->spec.sc.bond_list = 1;
            break;
        case OPT_OVERLAP:
            o->spec.sc.allow_overlap = 1;
            break;
        case OPT_STRICT:
            o->strict = 1;
            break;
        case OPT_NO_FAILURE: {
            pd_scene *sc = &o->spec.sc;
            if (strlen(optarg) >= PD_SET_NAME_MAX || !pd_set_name_ok(optarg))
                return usage_error("--no-failure needs a set name, not", optarg);
            int seen = 0;
            for (int k = 0; k < sc->nno_failure; k++)
                seen |= strcmp(sc->no_failure[k], optarg) == 0;
            if (seen) /* a scene file and the command line may both say it */
                break;
            if (sc->nno_failure == PD_NO_FAILURE_MAX)
                return usage_error("too many --no-failure sets", NULL);
            snprintf(sc->no_failure[sc->nno_failure++], PD_SET_NAME_MAX, "%s", optarg);
            break;
        }
        case OPT_DAMPING: {
            const char *comma = strchr(optarg, ',');
            char num[64];
            size_t len = comma ? (size_t)(comma - optarg) : strlen(optarg);
            snprintf(num, sizeof num, "%.*s", (int)(len < 63 ? len : 63), optarg);
            double *c = &o->spec.sc.damping;
            if (len >= 63 || !pd_parse_double(num, c) || !(*c > 0) ||
                (comma && (strlen(comma + 1) >= PD_SET_NAME_MAX || !pd_set_name_ok(comma + 1))))
                return usage_error("--damping needs C[,SET], C > 0 in 1/s and SET a set name, not",
                                   optarg);
            snprintf(o->spec.sc.damping_set, PD_SET_NAME_MAX, "%s", comma ? comma + 1 : "");
            break;
        }
        case OPT_BALANCE:
            if (strcmp(optarg, "off") == 0)
                o->spec.sc.balance_limit = -1;
            else if (!pd_parse_double(optarg, &o->spec.sc.balance_limit) ||
                     !(o->spec.sc.balance_limit > 0))
                return usage_error("--balance-limit must be a positive number or 'off', not",
                                   optarg);
            break;
        case OPT_FORCE_DT:
            o->spec.force_dt = 1;
            break;
        case OPT_EVERY:
            if (!pd_parse_int64(optarg, &iv) || iv < 0)
                return usage_error("--every must be a non-negative integer, not", optarg);
            o->spec.sc.every = iv;
            break;
        case OPT_THREADS:
            if (!pd_parse_int64(optarg, &iv) || iv < 1 || iv > 4096)
                return usage_error("--threads must be a positive integer, not", optarg);
            o->spec.sc.threads = (int)iv;
            break;
        case OPT_STATUS:
            if (!pd_parse_int64(optarg, &iv) || iv < 1)
                return usage_error("--status must be a positive integer, not", optarg);
            o->status_every = iv;
            o->has_status = 1;
            break;
        case OPT_RELAX:
            o->spec.sc.relax = 1;
            break;
        case OPT_RELAX_TOL:
            if ((rc = positive("--relax-tolerance", optarg, &o->spec.sc.relax_tolerance)))
                return rc;
            if (o->spec.sc.relax_tolerance >= 1)
                return usage_error("--relax-tolerance must be below 1, not", optarg);
            break;
        case OPT_RELAX_IT:
            if (!pd_parse_int64(optarg, &iv) || iv < 1)
                return usage_error("--relax-iterations must be a positive integer, not", optarg);
            o->spec.sc.relax_iterations = iv;
            break;
        case OPT_SERIES:
            if (!pd_parse_int64(optarg, &iv) || iv < 1)
                return usage_error("--series must be a positive integer, not", optarg);
            o->series_every = iv;
            break;
        case OPT_TIMING:
            o->timing = 1;
            break;
        case 'o':
            o->output = optarg;
            o->has_output = 1;
            break;
        case OPT_RESTART:
            o->restart = optarg;
            break;
        case OPT_LOST:
            if ((rc = positive("--lost-margin", optarg, &o->spec.sc.lost_margin)))
                return rc;
            break;
        case OPT_FIELDS:
            if ((rc = parse_fields(optarg, &o->spec.sc.fields)))
                return rc;
            break;
        case OPT_VBC:
        case OPT_DBC:
        case OPT_BODY:
            if ((rc = parse_bc(o, c == OPT_VBC   ? PD_BC_VELOCITY
                                  : c == OPT_DBC ? PD_BC_DISPLACEMENT
                                                 : PD_BC_BODY_FORCE,
                               optarg)))
                return rc;
            break;
        case OPT_PROJECTILE: {
            double v[9]; /* X,Y,Z,R,MASS,VX,VY,VZ and maybe K */
            int hk = strncmp(optarg, "sphere,", 7) == 0 && pd_parse_doubles(optarg + 7, v, 9);
            if (!hk && (strncmp(optarg, "sphere,", 7) != 0 || !pd_parse_doubles(optarg + 7, v, 8)))
                return usage_error("--projectile needs sphere,X,Y,Z,R,MASS,VX,VY,VZ[,K], not",
                                   optarg);
            if (!(v[3] > 0) || !(v[4] > 0) || (hk && !(v[8] > 0)))
                return usage_error("--projectile radius R, mass MASS and stiffness K must be "
                                   "positive in",
                                   optarg);
            o->spec.sc.has_projectile = 1;
            for (int d = 0; d < 3; d++) {
                o->spec.sc.proj_center[d] = v[d];
                o->spec.sc.proj_velocity[d] = v[5 + d];
            }
            o->spec.sc.proj_radius = v[3];
            o->spec.sc.proj_mass = v[4];
            o->spec.sc.proj_k = hk ? v[8] : 0;
            o->spec.has_proj_k = hk;
            break;
        }
        case OPT_ELLIPSOID:
            if (o->spec.sc.nellipsoids == PD_ELLIPSOID_MAX)
                return usage_error("--ellipsoid is given at most 8 times; one more:", optarg);
            if (pd_ellipsoid_parse(optarg, &o->spec.sc.ellipsoid[o->spec.sc.nellipsoids]) != PD_OK)
                return usage_error("--ellipsoid needs UX,UY,UZ,A,B,ROLL with U nonzero and A, B "
                                   "in (0, 1], not",
                                   optarg);
            o->spec.sc.nellipsoids++;
            break;
        case OPT_MATERIAL:
        case OPT_INTERFACE:
            if ((rc = parse_law(o, c == OPT_INTERFACE, optarg)))
                return rc;
            break;
        case OPT_FIBRE:
            if ((rc = parse_fibre(&o->spec.sc, optarg)))
                return rc;
            break;
        case 'q':
            o->quiet = 1;
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if (!o->has_steps && !o->spec.has_time)
        return usage_error("--steps or --time is required", NULL);
    if (pd_scene_check(&o->spec) != PD_OK) /* the options each model takes */
        return usage_error(pd_errmsg(), NULL);
    if (o->restart) { /* the run file is the input and, without -o, the output */
        if (optind < argc)
            return usage_error("--restart takes no INPUT besides RUN.h5:", argv[optind]);
        o->input = o->restart;
        if (!o->has_output)
            o->output = o->restart;
        return 0;
    }
    if (optind != argc - 1)
        return usage_error(optind < argc ? "give exactly one INPUT" : "missing INPUT (a file or '-')",
                           NULL);
    o->input = argv[optind];
    return 0;
}

static void progress(int64_t step, int64_t steps, double elapsed)
{
    int width = 30, done = steps ? (int)((double)width * (double)step / (double)steps) : width;
    double eta = step ? elapsed * (double)(steps - step) / (double)step : 0;
    fprintf(stderr, "\r[");
    for (int k = 0; k < width; k++)
        fputc(k < done ? '#' : '.', stderr);
    fprintf(stderr, "] %3.0f%% step %lld/%lld ETA %.0f s ", steps ? 100.0 * (double)step / (double)steps : 100.0,
            (long long)step, (long long)steps, eta);
    fflush(stderr);
}

/* The status line, with the energy balance of this step's energies e; a
 * kinetic energy that ran away from the energy put in is flagged (once,
 * when `flag`: the energy alarm has not stopped the run). */
static void status_line(const pd_sim *sim, int64_t steps, int tty, const pd_energy *energy,
                        int flag)
{
    static int flagged;
    const pd_energy e = *energy;
    double ratio;
    /* the body's figures (every MPI rank takes part; rank 0 tells) */
    const int64_t broken = pd_sim_broken(sim), lost = pd_sim_lost(sim);
    const double max_damage = pd_sim_max_damage(sim);
    if (pd_comm_rank() > 0)
        return;
    if (flag && !flagged && pd_energy_runaway(sim, &e, &ratio)) {
        fprintf(stderr,
                "%s" PROG ": warning: at step %lld the kinetic energy is %.3g times the energy "
                "put in (step 0 and the work done): the run is unstable; try a smaller time "
                "step or contact stiffness\n",
                tty ? "\r\033[K" : "", (long long)pd_sim_stepno(sim), ratio);
        flagged = 1;
    }
    fprintf(stderr,
            "%s" PROG ": step %lld/%lld t=%.6e s KE=%.6e J elastic=%.6e J contact=%.6e J "
            "released=%.6e J work=%.6e J balance=%.6e J broken=%lld max_damage=%.4f\n",
            tty ? "\r\033[K" : "", (long long)pd_sim_stepno(sim), (long long)steps,
            pd_sim_time(sim), e.kinetic, e.elastic, e.contact, e.released, e.work,
            pd_energy_total(&e), (long long)broken, max_damage);
    double px[3], pv[3];
    if (pd_sim_projectile(sim, px, pv))
        fprintf(stderr, PROG ": projectile at (%.6e, %.6e, %.6e) m, velocity (%.6e, %.6e, %.6e) "
                        "m/s, kinetic energy %.6e J\n",
                px[0], px[1], px[2], pv[0], pv[1], pv[2], e.projectile);
    if (pd_sim_damping(sim) > 0)
        fprintf(stderr, PROG ": damping took %.6e J so far\n", e.damped);
    if (e.lost > 0 || lost > 0)
        fprintf(stderr, PROG ": %lld particles lost so far, carrying %.6e J\n", (long long)lost,
                e.lost);
}

/* A frame, its time booked as output's. */
static pd_status timed_frame(pd_file *out, const pd_sim *sim, unsigned fields, double *t_out,
                             pd_energy *energy)
{
    double t0 = pd_wtime();
    pd_status s = pd_run_file_frame(out, sim, fields, energy);
    *t_out += pd_wtime() - t0;
    return s;
}

/* The time series' row of the step, with the energies it took (e may be
 * NULL), its time booked as output's. */
static pd_status timed_sample(pd_file *out, pd_sim *sim, double *t_out, pd_energy *e)
{
    double t0 = pd_wtime();
    pd_energy mine;
    pd_energy *energy = e ? e : &mine;
    pd_status s = pd_sim_energy(sim, energy, NULL);
    if (s == PD_OK)
        s = pd_run_file_sample(out, sim, energy);
    *t_out += pd_wtime() - t0;
    return s;
}

/* spread: on MPI ranks the least and the most over the ranks of the bonds'
 * and of the ranks' time (else NULL). */
static void print_timing(const pd_sim *sim, double wall, double output, const double *spread)
{
    static const char *names[PD_T_COUNT] = {"bonds",  "contact", "neighbour lists", "indenter",
                                            "integration", "output", "failure", "MPI ranks"};
    double t[PD_T_COUNT];
    memcpy(t, pd_sim_timers(sim), sizeof t);
    t[PD_T_OUTPUT] = output;
    fprintf(stderr, PROG ": timing (wall %.3f s)\n", wall);
    for (int k = 0; k < PD_T_COUNT - (pd_comm_size() == 1); k++) /* one rank: no MPI line */
        fprintf(stderr, "  %-16s %10.3f s %6.1f%%\n", names[k], t[k],
                wall > 0 ? 100.0 * t[k] / wall : 0.0);
    if (spread) /* a rank that walks its bonds faster waits for the others */
        fprintf(stderr,
                "  over the ranks: bonds %.3f to %.3f s, MPI ranks %.3f to %.3f s (rank 0's "
                "above)\n",
                spread[0], spread[1], spread[2], spread[3]);
}

/* The constants the run uses, and where they come from. */
static void log_constants(const pd_particles *p, const pd_scene *sc, const struct options *o)
{
    if (p->dimension == 2)
        fprintf(stderr,
                PROG ": a 2-D plate of thickness %g m: plane-stress PMB constants (nu = 1/3), "
                     "c = 12K/(pi H delta^3) = 9E/(pi H delta^3)\n",
                p->thickness);
    if (o->spec.has_e)
        fprintf(stderr, PROG ": Young's modulus %g Pa: bulk modulus %g Pa (%s), c %.6g N/m^6\n",
                sc->youngs_modulus, sc->bulk_modulus,
                p->dimension == 2 ? "K = 3E/4, plane stress" : "K = 2E/3, nu = 1/4", sc->c);
    else if (o->spec.has_k)
        fprintf(stderr, PROG ": bulk modulus %g Pa%s: c %.6g N/m^6\n", sc->bulk_modulus,
                p->dimension == 2 ? " (2-D, plane stress)" : "", sc->c);
    if (o->spec.has_g0)
        fprintf(stderr,
                PROG ": critical stretch s00 %.6g from the fracture energy G0 %g J/m^2 (%s), "
                     "alpha %g\n",
                sc->s00, o->spec.g0,
                p->dimension == 2 ? "2-D: sqrt(4 G0/(c H delta^4))" : "seed 004 eq. 27",
                sc->alpha);
}

struct held {
    pd_file *in, *out;
    pd_particles *p;
    pd_bonds *b;
    pd_sim *sim;   /* the whole body's run (NULL on several MPI ranks)  */
    pd_sim *piece; /* NULL, or on several MPI ranks this rank's piece of
                      the body, which steps (pd_sim_piece_new)         */
    pd_sets *sets;
    pd_restart r;
    double *v0[3];
    uint64_t *bits0;
    char *cmdline, *text;
    struct options *opts; /* its profiles */
    pd_scene_report report; /* a fresh run's scene at t = 0 */
    double t_setup;          /* its step 0 (pd_sim_setup), s */
    int64_t nbonds;          /* the whole body's directed bonds */
    int64_t iterations;      /* --relax: the iterations of its load steps */
    int64_t nofail;          /* particles of the --no-failure sets */
    int rows;                /* on MPI ranks each read a window of the body:
                                1 its own rows' bonds, 2 a lattice's
                                (pd_body_read)                           */
    pd_particles shape;      /* the body's count, dimension, spacing and
                                thickness, for the log (no arrays)       */
};

static void release(struct held *h)
{
    if (h->out != h->in)
        pd_file_close(h->in);
    pd_sim_free(h->piece);
    pd_sim_free(h->sim);
    pd_bonds_free(h->b);
    pd_sets_free(h->sets);
    pd_particles_free(h->p);
    pd_restart_free(&h->r);
    for (int d = 0; d < 3; d++)
        free(h->v0[d]);
    free(h->bits0);
    free(h->cmdline);
    free(h->text);
    if (h->opts)
        free_bc(h->opts);
}

/* The options: the scene file's (or a restart's run's) first, then the
 * command line's.  Returns 0 or the exit status. */
static int options(int argc, char **argv, struct options *o)
{
    int nargc = 0;
    char **nargv = NULL;
    memset(o, 0, sizeof *o);
    int rc = expand_scene(argc, argv, &nargc, &nargv);
    if (rc)
        return rc;
    rc = parse_options(nargc, nargv, o);
    free(nargv);
    if (rc == 0 && o->restart) { /* the steps to add must be said */
        int given = 0;
        for (int k = 1; k < argc; k++)
            given |= strcmp(argv[k], "--steps") == 0 || strncmp(argv[k], "--steps=", 8) == 0;
        if (!given)
            rc = usage_error("--restart needs --steps N, the steps to add", NULL);
    }
    return rc;
}

/* The log of the run's set-up: sizes, effects, dt, the kernel, the
 * constants and where they come from, the boundary conditions. */
static void log_scene(const struct options *o, const struct held *h, int64_t first,
                      int64_t nsteps)
{
    const pd_particles *p = &h->shape;
    const pd_scene *sc = &o->spec.sc;
    const pd_sim *sim = h->piece ? h->piece : h->sim; /* what the whole body's run would be */
    fprintf(stderr,
            PROG ": %lld particles, %lld bonds; effects: %s\n" PROG
                 ": dt %.6g s (stable step %.6g s, seed 004 eq. 46), %lld steps%s\n",
            (long long)p->n, (long long)(h->nbonds / 2), pd_sim_effects(sim), sc->dt,
            sc->dt_stable, (long long)nsteps, o->restart ? " more" : "");
    const char *wait = getenv("OMP_WAIT_POLICY"), *spin = getenv("GOMP_SPINCOUNT");
    if (pd_comm_mpi()) /* the MPI build: ranks x threads */
        fprintf(stderr, PROG ": %d MPI rank%s x ", pd_comm_size(), pd_comm_size() > 1 ? "s" : "");
    else
        fprintf(stderr, PROG ": ");
    fprintf(stderr, "%d thread%s%s%s%s%s\n", sc->threads, sc->threads > 1 ? "s" : "",
            wait ? ", OMP_WAIT_POLICY=" : "", wait ? wait : "", spin ? ", GOMP_SPINCOUNT=" : "",
            spin ? spin : "");
    if (pd_sim_stencil(sim) > 0)
        fprintf(stderr, PROG ": bonds walked as a lattice stencil of %d offsets%s%s\n",
                pd_sim_stencil(sim), pd_sim_stencil_tiles(sim) ? " in AVX-512 tiles" : "",
                sc->has_contact ? ", with the contact of its pairs" : "");
    else if (pd_sim_list_rows(sim))
        fprintf(stderr, PROG ": bonds walked as a bond list in AVX-512 rows%s%s\n",
                pd_sim_list_lanes(sim) ? ", 8 at a time in lanes" : "",
                sc->has_contact ? ", with the contact of its pairs" : "");
    log_constants(p, sc, o);
    if (sc->relax)
        fprintf(stderr,
                PROG ": --relax: %lld load steps of %g s, each relaxed by %s (iterations of "
                     "%.6g s, the stable step x %g) to a residual of %g times the load, in at "
                     "most %lld iterations\n",
                (long long)nsteps, sc->dt,
                sc->damping > 0 ? "dynamic relaxation with the fixed --damping"
                                : "adaptive dynamic relaxation",
                sc->relax_dt, sc->safety, sc->relax_tolerance, (long long)sc->relax_iterations);
    if (sc->nno_failure > 0) {
        fprintf(stderr, PROG ": --no-failure");
        for (int k = 0; k < sc->nno_failure; k++)
            fprintf(stderr, " %s", sc->no_failure[k]);
        fprintf(stderr, ": no bond of their %lld particles breaks\n",
                (long long)h->nofail);
    }
    if (sc->damping > 0 && sc->relax)
        fprintf(stderr, PROG ": --damping %g 1/s: the relaxation's damping\n", sc->damping);
    else if (sc->damping > 0)
        fprintf(stderr, PROG ": --damping %g 1/s (-C rho v) on %s\n", sc->damping,
                sc->damping_set[0] ? sc->damping_set : "every particle");
    for (int k = 0; k < o->nbc; k++) {
        const pd_set *set = pd_sets_find(h->sets, o->bc[k].set);
        char *prof = pd_profile_text(&o->bc[k].profile);
        fprintf(stderr, PROG ": --%s %s,%c,%s on %lld particles (%s)\n",
                pd_bc_option(o->bc[k].kind), o->bc[k].set, 'x' + o->bc[k].axis,
                prof ? prof : "?", (long long)(set ? set->n : 0),
                o->bc[k].kind == PD_BC_VELOCITY       ? "velocity held, m/s"
                : o->bc[k].kind == PD_BC_DISPLACEMENT ? "displacement held, m"
                                                      : "force density, N/m^3");
        free(prof);
    }
    char text[512];
    if (pd_model_describe(pd_model_of(sc->model), sc, text, sizeof text))
        fprintf(stderr, PROG ": %s\n", text);
    if (sc->nellipsoids > 0)
        fprintf(stderr, PROG ": anisotropic influence (seed 002 eq. 13): omega times the largest "
                             "distance to %d ellipsoid%s\n",
                sc->nellipsoids, sc->nellipsoids > 1 ? "s" : "");
    if (sc->has_projectile && !o->restart)
        fprintf(stderr,
                PROG ": projectile: mass %g kg, radius %g m, stiffness K %.6g N/m^5%s\n",
                sc->proj_mass, sc->proj_radius, sc->proj_k,
                o->spec.has_proj_k ? "" : " (default: 2 K p = the largest bond stiffness sum of "
                                          "seed 004 eq. 46 at p = spacing/4)");
    for (int k = 0; k < h->report.nwarnings; k++) /* the checks before step 1 */
        fprintf(stderr, PROG ": warning: %s\n", h->report.warning[k]);
    if (o->restart)
        fprintf(stderr, PROG ": going on from step %lld of '%s'\n", (long long)first, o->restart);
    else if (isfinite(h->report.contact_time))
        fprintf(stderr, PROG ": first contact at t = %.3g s (step %lld); %lld frame%s to write\n",
                h->report.contact_time, (long long)ceil(h->report.contact_time / sc->dt),
                (long long)h->report.frames, h->report.frames == 1 ? "" : "s");
    else
        fprintf(stderr, PROG ": %lld frame%s to write\n", (long long)h->report.frames,
                h->report.frames == 1 ? "" : "s");
}

/* The whole body and its restart data, once a rank steps its piece. */
static void drop_whole(struct held *h)
{
    pd_bonds_free(h->b);
    pd_particles_free(h->p);
    pd_restart_free(&h->r);
    memset(&h->r, 0, sizeof h->r);
    for (int d = 0; d < 3; d++) {
        free(h->v0[d]);
        h->v0[d] = NULL;
    }
    free(h->bits0);
    h->b = NULL;
    h->p = NULL;
    h->bits0 = NULL;
}

/* A fresh run's step 0 (pd_sim_setup), before its file is made: a start
 * that is mostly penalty energy is one more warning of the scene's. */
static pd_status start_energy(struct held *h)
{
    double t0 = pd_wtime();
    pd_sim *sim = h->piece ? h->piece : h->sim;
    pd_status s = pd_sim_setup(sim);
    h->t_setup = pd_wtime() - t0; /* the run's wall clock, as before */
    pd_scene_report *r = &h->report;
    if (s == PD_OK && r->nwarnings < PD_SCENE_WARNINGS &&
        pd_sim_start_penalty(sim, r->warning[r->nwarnings], sizeof r->warning[0]))
        r->nwarnings++;
    return s;
}

/* A status line every this many steps of a run of nsteps. */
static int64_t status_interval(const struct options *o, int64_t nsteps)
{
    return o->has_status ? o->status_every : (nsteps >= 10 ? nsteps / 10 : 1);
}

/* Read the body (a restart: the run and its last frame), resolve the
 * scene, set up the run and its file (published before the first step).
 * Returns 0, or the exit status after printing the error. */
static int start(struct options *o, struct held *h, int64_t *first)
{
    const int restart = o->restart != NULL, ranks = pd_comm_size() > 1;
    /* a restart updates the run (through a copy renamed over it; on MPI
     * ranks every rank reads the run as it was, and the copy is made when
     * the ranks have their pieces) */
    pd_status s = restart && !ranks ? pd_file_update(o->restart, o->output, &h->in)
                                    : pd_file_open(restart ? o->restart : o->input, &h->in);
    /* on MPI ranks each rank its piece's rows, particles and bonds, as a
     * window of the body where it can (collective) */
    pd_body_read w = {0};
    if (ranks)
        s = cli_agreed(s);
    if (s == PD_OK && ranks)
        s = pd_read_body_ranks(h->in, &o->spec, &h->p, &h->b, &w);
    else if (s == PD_OK && (s = pd_read_particles(h->in, &h->p)) == PD_OK)
        s = pd_read_bonds_compact(h->in, h->p, &h->b);
    const int rows = w.rows;
    h->rows = rows;
    if (s == PD_OK) { /* the body's figures for the log, whatever is cut */
        h->shape = (pd_particles){.n = pd_body_count(h->p), .spacing = h->p->spacing,
                                  .dimension = h->p->dimension, .thickness = h->p->thickness};
        h->shape.total = h->shape.own_hi = h->shape.n;
    }
    if (ranks) /* the scene's figures below are taken over the ranks */
        s = cli_agreed(s);
    if (s == PD_OK)
        s = pd_read_sets(h->in, h->p, &h->sets);
    pd_scene *sc = &o->spec.sc;
    sc->nbc = o->nbc;
    sc->bc = o->bc;
    sc->sets = h->sets;
    if (s == PD_OK)
        s = pd_scene_resolve(&o->spec, h->p, h->b, o->input);
    if (s == PD_OK && !restart)
        s = pd_scene_inspect(&o->spec, h->p, h->b, &h->report);
    if (s == PD_OK && restart) { /* on MPI ranks the bond states now, the rows below */
        s = ranks ? pd_run_file_load_state(h->in, h->b, &w, first, &h->bits0)
                  : pd_run_file_load(h->in, h->p, h->b, first, &h->r, h->v0, &h->bits0);
        sc->steps += *first; /* --steps N more */
    }
    /* a row of the series every --series N steps, by default the status
     * interval (not a line of the scene's text: a restart takes its own) */
    sc->series = o->series_every > 0 ? o->series_every : status_interval(o, sc->steps - *first);
    if (s == PD_OK && !ranks)
        s = pd_sim_new(h->p, h->b, sc, &h->sim);
    if (s == PD_OK && restart && !ranks)
        s = pd_sim_restore(h->sim, *first, &h->r, h->v0, h->bits0);
    if (ranks) /* this rank's piece of the body, without the whole body's run */
        s = cli_agreed(s);
    /* a window of the body: the piece takes it over (its bonds then in the
     * piece alone) */
    const int64_t n = h->p ? pd_body_count(h->p) : 0, nread = h->b ? h->b->count : 0;
    if (s == PD_OK && rows)
        s = pd_sim_piece_take(&h->p, &h->b, sc, restart ? h->bits0 : NULL, &h->piece);
    else if (s == PD_OK && ranks)
        s = pd_sim_piece_new(h->p, h->b, sc, restart ? h->bits0 : NULL, &h->piece);
    if (restart && ranks) { /* the piece's rows of the last frame and restart slot */
        int64_t g0 = 0, g1 = 0;
        s = cli_agreed(s);
        if (s == PD_OK) {
            pd_sim_piece_rows(h->piece, &g0, &g1);
            s = pd_run_file_load_rows(h->in, n, g0, g1 - g0, rows == 1 ? w.first_bond : 0,
                                      rows == 1 ? nread : -1, &h->r, h->v0);
        }
        s = cli_agreed(s);
        if (s == PD_OK)
            s = pd_sim_piece_restore(h->piece, h->p, h->b, *first, &h->r, g0, h->v0);
    }
    s = cli_agreed(s);
    if (s == PD_OK && !restart) /* step 0's forces, and the check of its energy */
        s = start_energy(h);
    if (s == PD_OK && o->strict && h->report.nwarnings > 0)
        s = pd_fail(PD_ERR_INVALID, "%s (--strict)", h->report.warning[0]);
    if (s == PD_OK && (h->text = pd_scene_text(sc)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the scene's text");
    s = cli_agreed(s);
    /* the run file, written by every rank (parallel HDF5 on MPI ranks) */
    if (s == PD_OK && restart && !ranks)
        h->out = h->in; /* the same file goes on */
    else if (s == PD_OK && restart)
        s = pd_file_update_ranks(o->restart, o->output, &h->out);
    else if (s == PD_OK)
        s = pd_file_create_ranks(o->output, &h->out);
    /* the whole body's bonds: a piece that read its own rows' writes them */
    pd_part part = {0};
    if (rows) { /* the piece's own rows (collective) */
        s = cli_agreed(s);
        if (s == PD_OK)
            pd_sim_part(h->piece, &part);
    }
    h->nbonds = rows ? part.nbonds : h->b ? h->b->count : 0;
    const pd_sim *run = h->piece ? h->piece : h->sim;
    const char *effects = run ? pd_sim_effects(run) : NULL;
    if (s == PD_OK && rows)
        s = pd_run_file_start_part(h->out, restart, restart ? h->out : h->in,
                                   pd_sim_particles(h->piece), pd_sim_bonds(h->piece), &part,
                                   h->sets, sc, effects, h->cmdline ? h->cmdline : PROG, h->text,
                                   *first);
    else if (s == PD_OK)
        s = pd_run_file_start(h->out, restart, restart ? h->out : h->in, h->p, h->b, h->sets,
                              sc, effects, h->cmdline ? h->cmdline : PROG, h->text, *first);
    s = cli_agreed(s);
    if (!restart || ranks) { /* read only (one rank's restart: the copy that goes on) */
        pd_file_close(h->in);
        h->in = NULL;
    }
    if (s == PD_OK && sc->nno_failure > 0) /* collective */
        h->nofail = h->piece ? pd_comm_total(pd_sim_no_failure(h->piece))
                             : pd_sim_no_failure(h->sim);
    if (s == PD_OK && h->piece && pd_comm_rank() > 0)
        drop_whole(h); /* rank 0's tells the run's set-up, then goes too */
    if (s != PD_OK) {
        if (h->out)
            pd_file_abort(h->out);
        else if (h->in) /* a restart's copy */
            pd_file_abort(h->in);
        h->in = h->out = NULL;
        return cli_failed();
    }
    return 0;
}

/* The steps from first + 1, with frames, status lines, the time series'
 * rows and the progress bar; the file stays open. */
static pd_status run_steps(const struct options *o, struct held *h, int64_t first, double *t_output)
{
    const pd_scene *sc = &o->spec.sc;
    /* the run, or on MPI ranks this rank's piece: every rank steps, sums,
     * and writes its rows of each frame; rank 0 tells */
    pd_sim *sim = h->piece ? h->piece : h->sim;
    const int root = pd_comm_rank() == 0;
    const int64_t nsteps = sc->steps - first;
    const int64_t status_every = status_interval(o, nsteps);
    const int tty = isatty(STDERR_FILENO) && !o->quiet && root;
    double t_start = pd_wtime(), t_shown = 0;
    pd_status s = PD_OK;
    if (!o->restart && pd_frame_at(sc, 0)) /* pd_sim_setup came in start() */
        s = timed_frame(h->out, sim, sc->fields, t_output, NULL);
    else if (!o->restart) /* the series' row of step 0 */
        s = timed_sample(h->out, sim, t_output, NULL);
    s = cli_agreed(s);
    int64_t lost = pd_sim_lost(sim);
    for (int64_t n = first + 1; n <= sc->steps && s == PD_OK; n++) {
        const int status = ((n - first) % status_every == 0 || n == sc->steps) && !o->quiet;
        const int row = pd_run_file_sample_due(h->out, n);
        const int output = status || row || pd_frame_at(sc, n);
        if (output) /* the bond pass counts the energies */
            pd_sim_energy_next(sim);
        pd_relax_info relaxed;
        s = sc->relax ? pd_sim_relax(sim, &relaxed) : pd_sim_step(sim);
        if (s != PD_OK)
            break;
        if (!output)
            continue;
        h->iterations += sc->relax ? relaxed.iterations : 0;
        if (sc->relax && status && root)
            fprintf(stderr,
                    "%s" PROG ": load step %lld: relaxed in %lld iterations (%lld times "
                    "again after bonds broke), residual %.3e N of a load of %.3e N, kinetic "
                    "energy %.3e J (its peak %.3e J)\n",
                    tty ? "\r\033[K" : "", (long long)n, (long long)relaxed.iterations,
                    (long long)relaxed.rounds, relaxed.residual, relaxed.load, relaxed.kinetic,
                    relaxed.kinetic_peak);
        const int64_t now_lost = pd_sim_lost(sim);
        if (lost == 0 && now_lost > 0 && !o->quiet && root) /* the first; then counts */
            fprintf(stderr,
                    "%s" PROG ": step %lld: %lld particles lost (farther than %g m outside the "
                    "body's box): their bonds broken, at rest from now on\n",
                    tty ? "\r\033[K" : "", (long long)n, (long long)now_lost, sc->lost_margin);
        lost = now_lost;
        /* a frame first, so that a status line of the same step takes its
         * energies instead of another pass over the bonds */
        pd_energy e;
        int known = 0;
        if (pd_frame_at(sc, n)) { /* with the series' row of the step */
            s = timed_frame(h->out, sim, sc->fields, t_output, &e);
            known = s == PD_OK;
        } else if (row) {
            s = timed_sample(h->out, sim, t_output, &e);
            known = s == PD_OK;
        }
        double t0 = pd_wtime(); /* a status line's energy pass is output's time */
        if (s == PD_OK && status && !known)
            known = pd_sim_energy(sim, &e, NULL) == PD_OK;
        if (s == PD_OK && known) /* the energy alarm, on every balance taken */
            s = pd_sim_check_balance(sim, &e);
        if (status && known) /* with the alarm's step too */
            status_line(sim, sc->steps, tty, &e, s == PD_OK);
        *t_output += pd_wtime() - t0;
        s = cli_agreed(s);
        if (tty) {
            double now = pd_wtime();
            if (now - t_shown > 0.2 || n == sc->steps) {
                progress(n - first, nsteps, now - t_start);
                t_shown = now;
            }
        }
    }
    if (tty)
        fputc('\n', stderr);
    return s;
}

/* Close the run file: a run that went non-finite keeps the frames written
 * before; any other failure leaves nothing under the final name. */
static pd_status finish(struct held *h, pd_status s)
{
    if (s == PD_OK || s == PD_ERR_UNSTABLE) {
        pd_status c = pd_file_close(h->out);
        if (c != PD_OK)
            s = c;
    } else
        pd_file_abort(h->out);
    h->in = h->out = NULL;
    return s;
}

static int run_main(int argc, char **argv);

/* The threads of a rank by default: the cores shared among the ranks of
 * this node (Open MPI names their count). */
static void rank_threads(const struct options *o)
{
    const char *local = getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
    int64_t k;
    if (o->spec.sc.threads > 0 || getenv("OMP_NUM_THREADS") || !local ||
        !pd_parse_int64(local, &k) || k <= 1)
        return;
    const int cores = omp_get_num_procs();
    omp_set_num_threads(cores / k > 1 ? (int)(cores / k) : 1);
}

int main(int argc, char **argv)
{
    pd_h5_debug(0); /* before any file is opened (a --restart reads its scene) */
    settle_threads(argv);
    if (cli_ranks_start(&argc, &argv) != 0)
        return 1;
    return cli_ranks_end(run_main(argc, argv));
}

static int run_main(int argc, char **argv)
{
    struct held h;
    memset(&h, 0, sizeof h);
    struct options o;
    h.cmdline = pd_join_argv(argc, argv);
    h.opts = &o;
    int rc = options(argc, argv, &o);
    if (rc == 0)
        rc = cli_ranks_files(o.input, o.restart ? "the run to go on from" : "the model",
                             o.output, "the run file");
    if (rc) {
        release(&h);
        return rc;
    }
    rank_threads(&o);
    pd_h5_debug(o.debug);
    remove_temps_on_signal();
    if (o.spec.sc.threads > 0)
        omp_set_num_threads(o.spec.sc.threads);
    o.spec.sc.threads = omp_get_max_threads();
    int64_t first = 0; /* the step the run starts from */
    if ((rc = start(&o, &h, &first))) {
        release(&h);
        return rc;
    }
    const int64_t nsteps = o.spec.sc.steps - first;
    /* the largest halo of a rank, and the largest piece (collective) */
    int64_t lo = 0, hi = 0;
    if (h.piece)
        pd_sim_owned(h.piece, &lo, &hi);
    const int64_t halo = -pd_comm_min(h.piece ? -pd_sim_halo_bytes(h.piece) : 0),
                  rows = -pd_comm_min(lo - hi);
    /* rank 0 tells (the others' stderr is /dev/null), from the whole body,
     * which then goes: each rank steps its piece */
    const int tell = !o.quiet && pd_comm_rank() == 0;
    if (tell)
        log_scene(&o, &h, first, nsteps);
    if (tell && h.piece)
        fprintf(stderr,
                PROG ": the body in %d pieces of at most %lld particles, each stepped with "
                     "its ghosts%s; halo of at most %.3g MB a rank a step; every rank writes "
                     "its rows of '%s' (parallel HDF5)\n",
                pd_comm_size(), (long long)rows,
                h.rows == 1   ? ", each read with its own rows' particles and bonds alone"
                : h.rows == 2 ? ", each read as its own window of the lattice"
                              : "",
                (double)halo / 1e6, o.output);
    if (h.piece)
        drop_whole(&h);
    const pd_sim *sim = h.piece ? h.piece : h.sim;
    double t_output = 0, t0 = pd_wtime();
    pd_status s = run_steps(&o, &h, first, &t_output);
    const double wall = pd_wtime() - t0 + h.t_setup;
    /* contact partners from beyond a piece, the most of a rank (collective) */
    const int64_t remote = h.piece ? -pd_comm_min(-pd_sim_contact_remote(h.piece)) : 0;
    s = cli_agreed(finish(&h, s));
    const double bonds = (double)h.nbonds;
    if (s == PD_OK && tell && o.spec.sc.relax)
        fprintf(stderr, PROG ": %lld load steps, %lld iterations, in %.3f s (%.3g bond "
                             "updates/s), contact list builds %lld\n",
                (long long)nsteps, (long long)h.iterations, wall,
                wall > 0 ? bonds * (double)(h.iterations + 2 * nsteps) / wall : 0.0,
                (long long)pd_sim_contact_builds(sim));
    else if (s == PD_OK && tell)
        fprintf(stderr, PROG ": %lld steps in %.3f s (%.3g bond updates/s), contact list builds %lld\n",
                (long long)nsteps, wall, wall > 0 ? bonds * (double)nsteps / wall : 0.0,
                (long long)pd_sim_contact_builds(sim));
    if (s == PD_OK && tell && h.piece && pd_sim_contact_builds(sim) > 0)
        fprintf(stderr, PROG ": contact across the ranks: at most %lld partners of a rank's list "
                             "from beyond its piece\n",
                (long long)remote);
    double spread[4]; /* the ranks' least and most bonds' and ranks' time (collective) */
    if (s == PD_OK && o.timing && h.piece) {
        const double *t = pd_sim_timers(sim);
        spread[0] = -pd_comm_max(-t[PD_T_BONDS]);
        spread[1] = pd_comm_max(t[PD_T_BONDS]);
        spread[2] = -pd_comm_max(-t[PD_T_RANKS]);
        spread[3] = pd_comm_max(t[PD_T_RANKS]);
    }
    if (s == PD_OK && o.timing && tell)
        print_timing(sim, wall, t_output, h.piece ? spread : NULL);
    release(&h);
    return s == PD_OK ? 0 : cli_failed();
}

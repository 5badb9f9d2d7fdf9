/*
 * pd-run -- integrate the peridynamic equation of motion for the effects a
 * scene declares.
 *
 * Velocity Verlet (seed 000 Algorithm 1) over the PMB bond force (seed 000
 * eqs. 5-7), with, only when declared: bond failure by critical stretch
 * (eqs. 8-9), short-range contact (eqs. 13-15) and a moving spherical
 * indenter (LAMMPS fix indent), a projectile the body pushes back
 * (lib/projectile.c, seed 004 section 6), and boundary conditions on the
 * particle sets of pd-lattice --set (seed 004 §2: body forces and
 * prescribed velocity or displacement in a layer).  The time step defaults to the stable step
 * of seed 004 eq. 46 times a safety factor; a larger --dt is refused.
 * Writes the model, the resolved scene (/scene) and frames (/frames).
 * A 2-D plate (/particles dimension 2) takes the plane-stress constants of
 * lib/plate.c: its --bulk-modulus is the 2-D bulk modulus.
 * --material, --interface and --fibre give bonds their own PMB constants
 * (lib/materials.c, seed 004 eq. 10).
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
#define MAX_LAWS 64

struct options {
    pd_scene sc;
    int has_g0;      /* --failure-energy: s00 from G0 once c is known */
    double g0;       /* J/m^2                                       */
    int has_e;       /* --youngs-modulus: K from E once the dimension is known */
    int has_proj_k;  /* --projectile with its K                     */
    int has_c, has_k, has_dt, has_steps, force_dt, has_status, has_output;
    int has_g, has_influence; /* --shear-modulus, --influence (LPS) */
    int has_lambda, has_tau;  /* --ves-lambda, --ves-tau (VES)      */
    int has_yield;            /* --yield-stress (EPS)               */
    int64_t status_every;
    const char *input;
    const char *output;
    const char *restart; /* --restart RUN.h5: go on from its last frame */
    int quiet, timing, debug;
    pd_bc bc[MAX_BC]; /* --velocity-bc, --displacement-bc, --body-force */
    int nbc;
    pd_bond_law laws[MAX_LAWS]; /* --material, --interface (a pair once:
                                   the last spec of it wins)           */
    double law_k[MAX_LAWS];     /* its K= (Pa), c resolved once the body
                                   is read; 0: c= was given            */
    int nlaws;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " [OPTION]... --steps N INPUT [-o FILE]\n"
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
            "  --contact-skin S      skin of the contact list, m (default spacing/2)\n"
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
            "  --dt DT               time step, s (default: stable step x safety)\n"
            "  --safety F            safety factor on the stable step (default 0.8)\n"
            "  --force-dt            run a --dt above the stable step anyway\n"
            "  --lost-margin D       a particle farther than D (m) outside the body's\n"
            "                        bounding box is lost: its bonds break and it stays\n"
            "                        at rest (default 10 x the box's largest edge)\n"
            "  --every N             a frame every N steps; 0 = only the last (default 0)\n"
            "Output:\n"
            "  --fields LIST         optional per-particle fields of each frame, a comma\n"
            "                        list of: energy (strain_energy_density, J/m^3),\n"
            "                        stress (the peridynamic stress tensor and its von\n"
            "                        Mises value, Pa)\n"
            "Other:\n"
            "  --restart RUN.h5      go on from the last complete frame of RUN.h5 for N\n"
            "                        more steps, with its scene (only --steps, --every,\n"
            "                        --threads, --status, --timing, -q, -o may be given);\n"
            "                        RUN.h5 is updated unless -o names another file\n"
            "  --scene FILE          read options from FILE ('option value' lines);\n"
            "                        the command line overrides it\n"
            "  --threads N           OpenMP threads (default: all cores)\n"
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
    while (slot < o->nlaws && !((o->laws[slot].a == law.a && o->laws[slot].b == law.b) ||
                                (o->laws[slot].a == law.b && o->laws[slot].b == law.a)))
        slot++;
    if (slot == MAX_LAWS)
        return usage_error("too many --material and --interface laws", NULL);
    o->laws[slot] = law;
    o->law_k[slot] = k;
    o->nlaws += slot == o->nlaws;
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

static void free_scene_strings(void)
{
    for (int k = 0; k < scene_count; k++)
        free(scene_strings[k]);
    free(scene_strings);
}

/* argv with the scene file's options first, then the command line's (so the
 * command line wins); the --scene option itself is dropped. */
/* May a --restart command line give this option?  Only what changes
 * neither the physics nor the steps already taken. */
static int restart_safe(const char *arg)
{
    static const char *safe[] = {"--restart", "--steps", "--every", "--threads", "--status",
                                 "--timing",  "-q",      "--quiet", "-o",        "--output",
                                 "--debug",   NULL};
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
        st = pd_scene_args_text(text, restart, &sc, &sv);
    else if (scene)
        st = pd_scene_args(scene, &sc, &sv);
    free(text);
    if (st != PD_OK)
        return fail();
    scene_strings = sv;
    scene_count = sc;
    atexit(free_scene_strings);
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
           OPT_INTERFACE, OPT_FIBRE, OPT_LAMBDA, OPT_TAU, OPT_YIELD, OPT_BONDLIST };
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
        {"dt", required_argument, 0, OPT_DT},
        {"safety", required_argument, 0, OPT_SAFETY},
        {"force-dt", no_argument, 0, OPT_FORCE_DT},
        {"bond-list", no_argument, 0, OPT_BONDLIST},
        {"every", required_argument, 0, OPT_EVERY},
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
    o->sc.model = PD_MODEL_PMB;
    o->sc.safety = 0.8;
    int c, rc, status = 0;
    int64_t iv;
    double ind[8];
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case OPT_MODEL:
            if (strcmp(optarg, "pmb") == 0)
                o->sc.model = PD_MODEL_PMB;
            else if (strcmp(optarg, "lps") == 0)
                o->sc.model = PD_MODEL_LPS;
            else if (strcmp(optarg, "ves") == 0)
                o->sc.model = PD_MODEL_VES;
            else if (strcmp(optarg, "eps") == 0)
                o->sc.model = PD_MODEL_EPS;
            else
                return usage_error("unknown --model (this pd knows: pmb, lps, ves, eps)", optarg);
            break;
        case OPT_LAMBDA:
            if (!pd_parse_double(optarg, &o->sc.ves_lambda) || !(o->sc.ves_lambda >= 0) ||
                !(o->sc.ves_lambda <= 1))
                return usage_error("--ves-lambda must be a number in [0, 1], not", optarg);
            o->has_lambda = 1;
            break;
        case OPT_TAU:
            if ((rc = positive("--ves-tau", optarg, &o->sc.ves_tau)))
                return rc;
            o->has_tau = 1;
            break;
        case OPT_YIELD:
            if ((rc = positive("--yield-stress", optarg, &o->sc.yield_stress)))
                return rc;
            o->has_yield = 1;
            break;
        case OPT_G:
            if ((rc = positive("--shear-modulus", optarg, &o->sc.shear_modulus)))
                return rc;
            o->has_g = 1;
            break;
        case OPT_INFLUENCE: {
            int w = pd_influence_parse(optarg);
            if (w < 0)
                return usage_error("--influence takes 1/r, 1 or gaussian, not", optarg);
            o->sc.influence = (pd_influence)w;
            o->has_influence = 1;
            break;
        }
        case OPT_C:
            if ((rc = positive("--c", optarg, &o->sc.c)))
                return rc;
            o->has_c = 1; /* the last of --c, --bulk-modulus and --youngs-modulus wins */
            o->has_k = 0;
            o->has_e = 0;
            break;
        case OPT_K:
            if ((rc = positive("--bulk-modulus", optarg, &o->sc.bulk_modulus)))
                return rc;
            o->has_k = 1;
            o->has_c = 0;
            o->has_e = 0;
            o->sc.youngs_modulus = 0;
            break;
        case OPT_E:
            if ((rc = positive("--youngs-modulus", optarg, &o->sc.youngs_modulus)))
                return rc;
            o->has_e = 1;
            o->has_c = 0;
            o->has_k = 0;
            break;
        case OPT_FAILURE: {
            double v[2];
            if (!pd_parse_doubles(optarg, v, 2) || !(v[0] > 0) || !(v[1] >= 0))
                return usage_error("--failure needs S00,ALPHA with S00 > 0 and ALPHA >= 0, not",
                                   optarg);
            o->sc.has_failure = 1;
            o->sc.s00 = v[0];
            o->sc.alpha = v[1];
            o->has_g0 = 0; /* the last of --failure and --failure-energy wins */
            break;
        }
        case OPT_G0: {
            double v[2] = {0, 0};
            if (!(pd_parse_doubles(optarg, v, 1) || pd_parse_doubles(optarg, v, 2)) ||
                !(v[0] > 0) || !(v[1] >= 0))
                return usage_error("--failure-energy needs G0[,ALPHA] with G0 > 0 (J/m^2) and "
                                   "ALPHA >= 0, not",
                                   optarg);
            o->sc.has_failure = 1;
            o->has_g0 = 1;
            o->g0 = v[0];
            o->sc.alpha = v[1];
            break;
        }
        case OPT_CONTACT:
            o->sc.has_contact = 1;
            break;
        case OPT_SKIN:
            if ((rc = positive("--contact-skin", optarg, &o->sc.contact_skin)))
                return rc;
            break;
        case OPT_INDENTER:
            if (strncmp(optarg, "sphere,", 7) != 0 || !pd_parse_doubles(optarg + 7, ind, 8))
                return usage_error("--indenter needs sphere,X,Y,Z,R,K,VX,VY,VZ, not", optarg);
            if (!(ind[3] > 0) || !(ind[4] > 0))
                return usage_error("--indenter radius R and stiffness K must be positive in",
                                   optarg);
            o->sc.has_indenter = 1;
            for (int d = 0; d < 3; d++) {
                o->sc.ind_center[d] = ind[d];
                o->sc.ind_velocity[d] = ind[5 + d];
            }
            o->sc.ind_radius = ind[3];
            o->sc.ind_k = ind[4];
            break;
        case OPT_STEPS:
            if (!pd_parse_int64(optarg, &iv) || iv < 0)
                return usage_error("--steps must be a non-negative integer, not", optarg);
            o->sc.steps = iv;
            o->has_steps = 1;
            break;
        case OPT_DT:
            if ((rc = positive("--dt", optarg, &o->sc.dt)))
                return rc;
            o->has_dt = 1;
            break;
        case OPT_SAFETY:
            if ((rc = positive("--safety", optarg, &o->sc.safety)))
                return rc;
            if (o->sc.safety > 1)
                return usage_error("--safety must not exceed 1, not", optarg);
            break;
        case OPT_BONDLIST:
            o->sc.bond_list = 1;
            break;
        case OPT_FORCE_DT:
            o->force_dt = 1;
            break;
        case OPT_EVERY:
            if (!pd_parse_int64(optarg, &iv) || iv < 0)
                return usage_error("--every must be a non-negative integer, not", optarg);
            o->sc.every = iv;
            break;
        case OPT_THREADS:
            if (!pd_parse_int64(optarg, &iv) || iv < 1 || iv > 4096)
                return usage_error("--threads must be a positive integer, not", optarg);
            o->sc.threads = (int)iv;
            break;
        case OPT_STATUS:
            if (!pd_parse_int64(optarg, &iv) || iv < 1)
                return usage_error("--status must be a positive integer, not", optarg);
            o->status_every = iv;
            o->has_status = 1;
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
            if ((rc = positive("--lost-margin", optarg, &o->sc.lost_margin)))
                return rc;
            break;
        case OPT_FIELDS:
            if ((rc = parse_fields(optarg, &o->sc.fields)))
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
            o->sc.has_projectile = 1;
            for (int d = 0; d < 3; d++) {
                o->sc.proj_center[d] = v[d];
                o->sc.proj_velocity[d] = v[5 + d];
            }
            o->sc.proj_radius = v[3];
            o->sc.proj_mass = v[4];
            o->sc.proj_k = hk ? v[8] : 0;
            o->has_proj_k = hk;
            break;
        }
        case OPT_ELLIPSOID:
            if (o->sc.nellipsoids == PD_ELLIPSOID_MAX)
                return usage_error("--ellipsoid is given at most 8 times; one more:", optarg);
            if (pd_ellipsoid_parse(optarg, &o->sc.ellipsoid[o->sc.nellipsoids]) != PD_OK)
                return usage_error("--ellipsoid needs UX,UY,UZ,A,B,ROLL with U nonzero and A, B "
                                   "in (0, 1], not",
                                   optarg);
            o->sc.nellipsoids++;
            break;
        case OPT_MATERIAL:
        case OPT_INTERFACE:
            if ((rc = parse_law(o, c == OPT_INTERFACE, optarg)))
                return rc;
            break;
        case OPT_FIBRE:
            if ((rc = parse_fibre(&o->sc, optarg)))
                return rc;
            break;
        case 'q':
            o->quiet = 1;
            break;
        default:
            return option_error(argv);
        }
    }
    if (status)
        return status;
    if (!o->has_steps)
        return usage_error("--steps is required", NULL);
    if (o->sc.model == PD_MODEL_VES) {
        if (!o->has_lambda || !o->has_tau)
            return usage_error("--model ves needs --ves-lambda and --ves-tau", NULL);
    } else if (o->has_lambda || o->has_tau)
        return usage_error(o->has_lambda ? "--ves-lambda is for --model ves"
                                         : "--ves-tau is for --model ves",
                           NULL);
    if (o->sc.model == PD_MODEL_EPS && !o->has_yield)
        return usage_error("--model eps needs --yield-stress", NULL);
    if (o->sc.model != PD_MODEL_EPS && o->has_yield)
        return usage_error("--yield-stress is for --model eps", NULL);
    if (pd_model_state_based(pd_model_of(o->sc.model))) {
        if (o->has_e)
            return usage_error("--youngs-modulus is for pmb (Poisson ratio 1/4); --model lps "
                               "takes --bulk-modulus and --shear-modulus",
                               NULL);
        if (o->has_c)
            return usage_error("--c is the PMB micromodulus; --model lps takes --bulk-modulus "
                               "and --shear-modulus",
                               NULL);
        if (!o->has_k || !o->has_g)
            return usage_error("--model lps needs --bulk-modulus and --shear-modulus", NULL);
        if (o->has_g0)
            return usage_error("--failure-energy derives s00 for PMB (seed 004 eq. 27); with "
                               "--model lps give --failure S00,ALPHA",
                               NULL);
    } else if (o->has_g || o->has_influence)
        return usage_error(o->has_g ? "--shear-modulus is for --model lps (PMB has Poisson "
                                      "ratio 1/4: only K)"
                                    : "--influence is for --model lps",
                           NULL);
    if (o->sc.nellipsoids > 0 && o->sc.model == PD_MODEL_PMB)
        return usage_error("--ellipsoid is an influence function of the state-based models "
                           "(--model lps)",
                           NULL);
    if (o->nlaws > 0 || o->sc.has_fibre) {
        if (o->sc.model != PD_MODEL_PMB)
            return usage_error("--material, --interface and --fibre are for --model pmb", NULL);
        int s00 = o->sc.fibre_s00[0] > 0;
        for (int k = 0; k < o->nlaws; k++)
            s00 |= o->laws[k].s00 > 0;
        if (s00 && !o->sc.has_failure)
            return usage_error("a critical stretch of --material, --interface or --fibre needs "
                               "--failure or --failure-energy (the scene's s00 and alpha)",
                               NULL);
        /* the scene's c: the fibres' matrix, else the stiffest material
         * (contact, and the materials without a law) */
        if (!o->has_c && !o->has_k && !o->has_e && o->sc.has_fibre)
            o->sc.c = o->sc.fibre_c[1], o->has_c = 1;
        for (int k = 0; k < o->nlaws && !o->has_c && !o->has_k && !o->has_e; k++)
            if (o->laws[k].a == o->laws[k].b && o->law_k[k] == 0)
                o->sc.c = fmax(o->sc.c, o->laws[k].c);
        if (o->sc.c > 0)
            o->has_c = 1;
        for (int k = 0; k < o->nlaws && !o->has_c && !o->has_k && !o->has_e; k++)
            if (o->laws[k].a == o->laws[k].b)
                o->sc.bulk_modulus = fmax(o->sc.bulk_modulus, o->law_k[k]);
        if (!o->has_c && o->sc.bulk_modulus > 0)
            o->has_k = 1;
    }
    if (!o->has_c && !o->has_k && !o->has_e)
        return usage_error("give the stiffness: --c or --bulk-modulus (or --youngs-modulus)", NULL);
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

/* The resolved scene in scene-file form, enough to rerun. */
static char *scene_text(const pd_scene *s)
{
    size_t cap = 2048 + 160 * (size_t)s->nellipsoids;
    char *prof[MAX_BC] = {NULL};
    for (int k = 0; k < s->nbc; k++) { /* a table in resolved form */
        if ((prof[k] = pd_profile_text(&s->bc[k].profile)) == NULL) {
            for (int m = 0; m < k; m++)
                free(prof[m]);
            return NULL;
        }
        cap += strlen(prof[k]) + 2 * PD_SET_NAME_MAX;
    }
    cap += (size_t)s->nlaws * 160 + 256;
    char *t = malloc(cap), *p = t;
    if (t == NULL) {
        for (int k = 0; k < s->nbc; k++)
            free(prof[k]);
        return NULL;
    }
    if (pd_model_state_based(pd_model_of(s->model)))
        p += sprintf(p, "model %s\nbulk-modulus %.17g\nshear-modulus %.17g\ninfluence %s\n",
                     s->model == PD_MODEL_VES   ? "ves"
                     : s->model == PD_MODEL_EPS ? "eps"
                                                : "lps",
                     s->bulk_modulus,
                     s->shear_modulus, pd_influence_name(s->influence));
    else
        p += sprintf(p, "model pmb\nc %.17g\n", s->c);
    for (int k = 0; k < s->nellipsoids; k++)
        p += sprintf(p, "ellipsoid %.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s->ellipsoid[k].u[0],
                     s->ellipsoid[k].u[1], s->ellipsoid[k].u[2], s->ellipsoid[k].a,
                     s->ellipsoid[k].b, s->ellipsoid[k].roll);
    if (s->model == PD_MODEL_VES)
        p += sprintf(p, "ves-lambda %.17g\nves-tau %.17g\n", s->ves_lambda, s->ves_tau);
    if (s->model == PD_MODEL_EPS)
        p += sprintf(p, "yield-stress %.17g\n", s->yield_stress);
    if (s->has_failure)
        p += sprintf(p, "failure %.17g,%.17g\n", s->s00, s->alpha);
    if (s->has_contact)
        p += sprintf(p, "contact\ncontact-skin %.17g\n", s->contact_skin);
    if (s->has_indenter)
        p += sprintf(p, "indenter sphere,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                     s->ind_center[0], s->ind_center[1], s->ind_center[2], s->ind_radius, s->ind_k,
                     s->ind_velocity[0], s->ind_velocity[1], s->ind_velocity[2]);
    if (s->has_projectile)
        p += sprintf(p,
                     "projectile sphere,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                     s->proj_center[0], s->proj_center[1], s->proj_center[2], s->proj_radius,
                     s->proj_mass, s->proj_velocity[0], s->proj_velocity[1], s->proj_velocity[2],
                     s->proj_k);
    for (int k = 0; k < s->nlaws; k++) { /* K= resolved to c */
        const pd_bond_law *l = &s->laws[k];
        if (l->a == l->b)
            p += sprintf(p, "material %d,c=%.17g", (int)l->a, l->c);
        else
            p += sprintf(p, "interface %d,%d,c=%.17g", (int)l->a, (int)l->b, l->c);
        p += l->s00 > 0 ? sprintf(p, ",s00=%.17g\n", l->s00) : sprintf(p, "\n");
    }
    if (s->has_fibre) {
        p += sprintf(p, "fibre %.17g,%.17g,%.17g,%.17g,%.17g", s->fibre_g[0], s->fibre_g[1],
                     s->fibre_g[2], s->fibre_c[0], s->fibre_c[1]);
        p += s->fibre_s00[0] > 0
                 ? sprintf(p, ",%.17g,%.17g\n", s->fibre_s00[0], s->fibre_s00[1])
                 : sprintf(p, "\n");
    }
    p += sprintf(p, "dt %.17g\nsteps %lld\nevery %lld\n", s->dt, (long long)s->steps,
                 (long long)s->every);
    if (s->fields)
        p += sprintf(p, "fields %s%s%s\n", s->fields & PD_FIELD_ENERGY ? "energy" : "",
                     s->fields == (PD_FIELD_ENERGY | PD_FIELD_STRESS) ? "," : "",
                     s->fields & PD_FIELD_STRESS ? "stress" : "");
    p += sprintf(p, "lost-margin %.17g\n", s->lost_margin);
    if (s->dt > s->dt_stable)
        p += sprintf(p, "force-dt\n");
    if (s->bond_list)
        p += sprintf(p, "bond-list\n");
    for (int k = 0; k < s->nbc; k++) {
        p += sprintf(p, "%s %s,%c,%s\n", pd_bc_option(s->bc[k].kind), s->bc[k].set,
                     'x' + s->bc[k].axis, prof[k]);
        free(prof[k]);
    }
    return t;
}

/* The steps after `first` that get a frame: every, 2 every, ... and the
 * last; only the last with --every 0; and step 0 itself in a new run
 * (`fresh`), not in a restart (even from step 0, whose frame exists). */
static pd_status plan_frames(pd_file *out, const pd_particles *p, const pd_bonds *b,
                             const pd_scene *sc, unsigned fields, int64_t first, int fresh)
{
    int64_t cap = sc->every > 0 ? sc->steps / sc->every + 2 : 1, m = 0;
    int64_t *steps = malloc((size_t)cap * sizeof *steps);
    double *times = malloc((size_t)cap * sizeof *times);
    if (steps == NULL || times == NULL) {
        free(steps);
        free(times);
        return pd_fail(PD_ERR_NOMEM, "out of memory planning %lld frames", (long long)cap);
    }
    if (sc->every > 0)
        for (int64_t n = 0; n <= sc->steps; n += sc->every)
            if (n > first || (n == 0 && fresh))
                steps[m++] = n;
    if ((m == 0 || steps[m - 1] != sc->steps) && (sc->steps > first || fresh))
        steps[m++] = sc->steps;
    for (int64_t k = 0; k < m; k++)
        times[k] = (double)steps[k] * sc->dt;
    pd_status s = pd_plan_frames(out, p->n, b->count, m, steps, times, fields);
    free(steps);
    free(times);
    return s;
}

/* The state at the last complete frame of a run: its step, the restart
 * slot, the frame's velocities and bond states. */
static pd_status load_restart(pd_file *f, const pd_particles *p, const pd_bonds *b,
                              int64_t *step, pd_restart *r, double *v[3], uint64_t **bits)
{
    int64_t nframes = 0;
    char **names = NULL;
    pd_status s = pd_list_frames(f, &nframes, &names);
    if (s == PD_OK && nframes == 0)
        s = pd_fail(PD_ERR_FORMAT, "the run has no complete frame to restart from");
    pd_frame_info fi;
    if (s == PD_OK)
        s = pd_read_frame_info(f, names[nframes - 1], &fi);
    for (int d = 0; d < 3 && s == PD_OK; d++)
        if ((v[d] = malloc((size_t)p->n * sizeof(double))) == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK && (*bits = calloc((size_t)pd_bits_words(b->count) + 1, 8)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK)
        s = pd_read_frame_vectors(f, names[nframes - 1], p->n, NULL, v);
    if (s == PD_OK)
        s = pd_read_frame_state(f, names[nframes - 1], b->count, *bits);
    if (s == PD_OK)
        s = pd_read_restart(f, p->n, fi.step, r);
    if (s == PD_OK)
        *step = fi.step;
    pd_frames_free_list(nframes, names);
    return s;
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

/* The status line, with the energy balance (`known`: the energies of
 * this step, already taken for its frame; NULL: taken here); a kinetic
 * energy that ran away from the energy put in is flagged (once). */
static void status_line(const pd_sim *sim, int64_t steps, int tty, const pd_energy *known)
{
    static int flagged;
    pd_energy e;
    double ratio;
    if (known)
        e = *known;
    else if (pd_sim_energy(sim, &e, NULL) != PD_OK)
        return;
    if (!flagged && pd_energy_runaway(sim, &e, &ratio)) {
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
            pd_energy_total(&e), (long long)pd_sim_broken(sim), pd_sim_max_damage(sim));
    double px[3], pv[3];
    if (pd_sim_projectile(sim, px, pv))
        fprintf(stderr, PROG ": projectile at (%.6e, %.6e, %.6e) m, velocity (%.6e, %.6e, %.6e) "
                        "m/s, kinetic energy %.6e J\n",
                px[0], px[1], px[2], pv[0], pv[1], pv[2], e.projectile);
    if (e.lost > 0 || pd_sim_lost(sim) > 0)
        fprintf(stderr, PROG ": %lld particles lost so far, carrying %.6e J\n",
                (long long)pd_sim_lost(sim), e.lost);
}

/* A frame and the restart data of this step; its energies go to *energy
 * as well (when not NULL). */
static pd_status write_frame(pd_file *out, const pd_particles *p, const pd_bonds *b,
                             const pd_sim *sim, unsigned fields, double *t_out,
                             pd_energy *energy)
{
    double t0 = pd_wtime();
    pd_frame_info fi = {.step = pd_sim_stepno(sim), .time = pd_sim_time(sim),
                        .broken = pd_sim_broken(sim), .lost = pd_sim_lost(sim)};
    fi.has_projectile = pd_sim_projectile(sim, fi.projectile_position, fi.projectile_velocity);
    size_t n = (size_t)(p->n > 0 ? p->n : 1);
    double *density = NULL, *stress = NULL, *mises = NULL;
    if ((fields & PD_FIELD_ENERGY) && (density = malloc(n * sizeof(double))) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the strain energy density");
    if ((fields & PD_FIELD_STRESS) && ((stress = malloc(9 * n * sizeof(double))) == NULL ||
                                       (mises = malloc(n * sizeof(double))) == NULL)) {
        free(density);
        free(stress);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the stress");
    }
    pd_status s = pd_sim_energy(sim, &fi.energy, density);
    if (s == PD_OK && stress) {
        s = pd_sim_stress(sim, stress);
        for (int64_t i = 0; i < p->n; i++)
            mises[i] = pd_von_mises(stress + 9 * i);
    }
    pd_frame_fields ff = {density, stress, mises};
    /* what a restart needs, then the frame (marked complete last) */
    pd_restart r;
    memset(&r, 0, sizeof r);
    pd_sim_accumulated(sim, &r);
    if (s == PD_OK)
        s = pd_write_restart(out, p->n, fi.step, &r);
    if (s == PD_OK)
        s = pd_write_frame(out, p, &fi, pd_sim_positions(sim), pd_sim_velocities(sim),
                           pd_sim_intact(sim), b->count, &ff);
    free(density);
    free(stress);
    free(mises);
    if (energy)
        *energy = fi.energy;
    *t_out += pd_wtime() - t0;
    return s;
}

static void print_timing(const pd_sim *sim, double wall, double output)
{
    static const char *names[PD_T_COUNT] = {"bonds", "contact", "neighbour lists", "indenter",
                                            "integration", "output", "failure"};
    double t[PD_T_COUNT];
    memcpy(t, pd_sim_timers(sim), sizeof t);
    t[PD_T_OUTPUT] = output;
    fprintf(stderr, PROG ": timing (wall %.3f s)\n", wall);
    for (int k = 0; k < PD_T_COUNT; k++)
        fprintf(stderr, "  %-16s %10.3f s %6.1f%%\n", names[k], t[k],
                wall > 0 ? 100.0 * t[k] / wall : 0.0);
}

/* The constants the run uses, and where they come from. */
static void log_constants(const pd_particles *p, const pd_scene *sc, const struct options *o)
{
    if (p->dimension == 2)
        fprintf(stderr,
                PROG ": a 2-D plate of thickness %g m: plane-stress PMB constants (nu = 1/3), "
                     "c = 12K/(pi H delta^3) = 9E/(pi H delta^3)\n",
                p->thickness);
    if (o->has_e)
        fprintf(stderr, PROG ": Young's modulus %g Pa: bulk modulus %g Pa (%s), c %.6g N/m^6\n",
                sc->youngs_modulus, sc->bulk_modulus,
                p->dimension == 2 ? "K = 3E/4, plane stress" : "K = 2E/3, nu = 1/4", sc->c);
    else if (o->has_k)
        fprintf(stderr, PROG ": bulk modulus %g Pa%s: c %.6g N/m^6\n", sc->bulk_modulus,
                p->dimension == 2 ? " (2-D, plane stress)" : "", sc->c);
    if (o->has_g0)
        fprintf(stderr,
                PROG ": critical stretch s00 %.6g from the fracture energy G0 %g J/m^2 (%s), "
                     "alpha %g\n",
                sc->s00, o->g0,
                p->dimension == 2 ? "2-D: sqrt(4 G0/(c H delta^4))" : "seed 004 eq. 27",
                sc->alpha);
}

/* Free what main holds. */
struct held {
    pd_file *in, *out;
    pd_particles *p;
    pd_bonds *b;
    pd_sim *sim;
    pd_sets *sets;
    pd_restart r;
    double *v0[3];
    uint64_t *bits0;
    char *cmdline, *text;
    struct options *opts; /* its profiles */
};

static void release(struct held *h)
{
    if (h->out != h->in)
        pd_file_close(h->in);
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

int main(int argc, char **argv)
{
    pd_h5_debug(0); /* before any file is opened (a --restart reads its scene) */
    struct held h;
    memset(&h, 0, sizeof h);
    h.cmdline = pd_join_argv(argc, argv);
    int nargc = 0;
    char **nargv = NULL;
    int rc = expand_scene(argc, argv, &nargc, &nargv);
    if (rc) {
        free(h.cmdline);
        return rc;
    }
    struct options o;
    rc = parse_options(nargc, nargv, &o);
    free(nargv);
    if (rc == 0 && o.restart) { /* the steps to add must be said */
        int given = 0;
        for (int k = 1; k < argc; k++)
            given |= strcmp(argv[k], "--steps") == 0 || strncmp(argv[k], "--steps=", 8) == 0;
        if (!given)
            rc = usage_error("--restart needs --steps N, the steps to add", NULL);
    }
    if (rc) {
        free_bc(&o);
        free(h.cmdline);
        return rc;
    }
    h.opts = &o;
    pd_h5_debug(o.debug);
    remove_temps_on_signal();
    if (o.sc.threads > 0)
        omp_set_num_threads(o.sc.threads);
    o.sc.threads = omp_get_max_threads();
    const int restart = o.restart != NULL;

    /* a restart updates the run (through a copy renamed over it) */
    pd_status s = restart ? pd_file_update(o.restart, o.output, &h.in)
                          : pd_file_open(o.input, &h.in);
    if (s == PD_OK)
        s = pd_read_particles(h.in, &h.p);
    if (s == PD_OK)
        s = pd_read_bonds(h.in, h.p, &h.b);
    if (s == PD_OK)
        s = pd_read_sets(h.in, h.p, &h.sets);
    if (s != PD_OK) {
        if (restart)
            pd_file_abort(h.in);
        else
            pd_file_close(h.in);
        h.in = NULL;
        release(&h);
        return fail();
    }
    pd_particles *p = h.p;
    pd_bonds *b = h.b;
    pd_scene *sc = &o.sc;
    sc->nbc = o.nbc;
    sc->bc = o.bc;
    sc->sets = h.sets;
    for (int k = 0; k < o.nlaws; k++) /* --material/--interface K=: c for the dimension */
        if (o.law_k[k] > 0)
            o.laws[k].c = pd_pmb_c_for(p, o.law_k[k], b->horizon);
    sc->nlaws = o.nlaws;
    sc->laws = o.laws;
    if (pd_scene_has_laws(sc) && pd_bond_laws_check(p, sc) != PD_OK) {
        if (restart)
            pd_file_abort(h.in), h.in = NULL;
        release(&h);
        return fail();
    }
    if (o.has_e) /* PMB's fixed Poisson ratio: K from E by dimension */
        sc->bulk_modulus = pd_pmb_bulk_from_youngs(sc->youngs_modulus, p->dimension);
    if (o.has_k || o.has_e)
        sc->c = pd_pmb_c_for(p, sc->bulk_modulus, b->horizon);
    if (!o.has_k && !o.has_e)
        sc->bulk_modulus = sc->youngs_modulus = 0; /* a scene's K or E that --c overrode */
    if (pd_model_state_based(pd_model_of(sc->model)) && p->dimension == 2) {
        fprintf(stderr, PROG ": error: --model %s is for 3-D bodies; '%s' is a 2-D plate (run "
                             "it with pmb)\n",
                sc->model == PD_MODEL_VES   ? "ves"
                : sc->model == PD_MODEL_EPS ? "eps"
                                            : "lps",
                o.input);
        if (restart)
            pd_file_abort(h.in), h.in = NULL;
        release(&h);
        return 1;
    }
    if (o.has_g0)
        sc->s00 = pd_pmb_s0_for(p, o.g0, sc->c, b->horizon);
    if (sc->has_contact && !(sc->contact_skin > 0))
        sc->contact_skin = 0.5 * p->spacing;
    if (!(sc->lost_margin > 0))
        sc->lost_margin = pd_lost_margin_default(p);
    sc->dt_stable = pd_stable_dt(p, b, sc);
    if (sc->has_projectile && !o.has_proj_k)
        sc->proj_k = pd_projectile_default_k(p, b, sc);
    if (!o.has_dt) {
        if (!isfinite(sc->dt_stable)) {
            fprintf(stderr, PROG ": error: no bonds, so no stable time step; give --dt\n");
            if (restart)
                pd_file_abort(h.in), h.in = NULL;
            release(&h);
            return 1;
        }
        sc->dt = sc->safety * sc->dt_stable;
    } else if (sc->dt > sc->dt_stable && !o.force_dt) {
        fprintf(stderr,
                PROG ": error: --dt %g s exceeds the stable time step %g s (seed 004 eq. 46); "
                     "use --force-dt to run anyway\n",
                sc->dt, sc->dt_stable);
        if (restart)
            pd_file_abort(h.in), h.in = NULL;
        release(&h);
        return 1;
    }
    int64_t first = 0; /* the step the run starts from */
    if (restart) {
        s = load_restart(h.in, p, b, &first, &h.r, h.v0, &h.bits0);
        sc->steps += first; /* --steps N more */
    }
    int64_t nsteps = sc->steps - first;
    int64_t status_every = o.has_status ? o.status_every : (nsteps >= 10 ? nsteps / 10 : 1);

    if (s == PD_OK)
        s = pd_sim_new(p, b, sc, &h.sim);
    if (s == PD_OK && restart)
        s = pd_sim_restore(h.sim, first, &h.r, h.v0, h.bits0);
    h.text = scene_text(sc);
    if (s == PD_OK && restart) {
        /* the same file goes on: unfinished frames out, the scene and the
         * history say what was added */
        h.out = h.in;
        s = pd_drop_incomplete_frames(h.out);
        if (s == PD_OK)
            s = pd_append_history(h.out, h.cmdline ? h.cmdline : PROG);
    } else if (s == PD_OK) {
        s = pd_file_create(o.output, &h.out);
        if (s == PD_OK)
            s = pd_write_header(h.out, h.in, h.cmdline ? h.cmdline : PROG);
        if (s == PD_OK)
            s = pd_write_particles(h.out, p);
        if (s == PD_OK)
            s = pd_write_bonds(h.out, b);
        if (s == PD_OK)
            s = pd_write_sets(h.out, h.sets);
    }
    if (s == PD_OK)
        s = pd_write_scene(h.out, sc, pd_sim_effects(h.sim), h.text ? h.text : "");
    /* every frame laid out now, then the file under its final name: a run
     * killed at any moment leaves it readable with its complete frames */
    if (s == PD_OK)
        s = plan_frames(h.out, p, b, sc,
                        o.sc.fields | (sc->has_projectile ? PD_FRAME_PROJECTILE : 0), first,
                        !restart);
    if (s == PD_OK)
        s = pd_plan_restart(h.out, p->n, sc->has_failure, sc->has_contact);
    if (s == PD_OK && sc->has_projectile)
        s = pd_plan_restart_projectile(h.out);
    if (s == PD_OK && sc->model == PD_MODEL_VES && b->count > 0)
        s = pd_plan_restart_history(h.out, b->count, 2);
    if (s == PD_OK && sc->model == PD_MODEL_EPS && b->count > 0)
        s = pd_plan_restart_history(h.out, b->count, 1);
    if (s == PD_OK)
        s = pd_file_publish(h.out);
    if (!restart) {
        pd_file_close(h.in);
        h.in = NULL;
    }
    if (s != PD_OK) {
        pd_file_abort(h.out ? h.out : h.in); /* h.in: a restart's copy */
        h.in = h.out = NULL;
        release(&h);
        return fail();
    }
    pd_sim *sim = h.sim;
    pd_file *out = h.out;
    int tty = isatty(STDERR_FILENO) && !o.quiet;
    if (!o.quiet)
        fprintf(stderr,
                PROG ": %lld particles, %lld bonds; effects: %s\n" PROG
                     ": dt %.6g s (stable step %.6g s, seed 004 eq. 46), %lld steps%s\n",
                (long long)p->n, (long long)(b->count / 2), pd_sim_effects(sim), sc->dt,
                sc->dt_stable, (long long)nsteps, restart ? " more" : "");
    if (!o.quiet && pd_sim_stencil(sim) > 0)
        fprintf(stderr, PROG ": bonds walked as a lattice stencil of %d offsets%s%s\n",
                pd_sim_stencil(sim), pd_sim_stencil_tiles(sim) ? " in AVX-512 tiles" : "",
                sc->has_contact ? ", with the contact of its pairs" : "");
    if (!o.quiet)
        log_constants(p, sc, &o);
    for (int k = 0; k < o.nbc && !o.quiet; k++) {
        const pd_set *set = pd_sets_find(h.sets, o.bc[k].set);
        char *prof = pd_profile_text(&o.bc[k].profile);
        fprintf(stderr, PROG ": --%s %s,%c,%s on %lld particles (%s)\n",
                pd_bc_option(o.bc[k].kind), o.bc[k].set, 'x' + o.bc[k].axis,
                prof ? prof : "?", (long long)(set ? set->n : 0),
                o.bc[k].kind == PD_BC_VELOCITY       ? "velocity held, m/s"
                : o.bc[k].kind == PD_BC_DISPLACEMENT ? "displacement held, m"
                                                     : "force density, N/m^3");
        free(prof);
    }
    if (!o.quiet && sc->model == PD_MODEL_LPS)
        fprintf(stderr,
                PROG ": model lps (seed 000 eqs. 3-4, Algorithms 2-4): K %g Pa, G %g Pa, "
                     "influence %s; contact stiffness from c = 18K/(pi delta^4)\n",
                sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence));
    if (!o.quiet && sc->nellipsoids > 0)
        fprintf(stderr, PROG ": anisotropic influence (seed 002 eq. 13): omega times the largest "
                             "distance to %d ellipsoid%s\n",
                sc->nellipsoids, sc->nellipsoids > 1 ? "s" : "");
    if (!o.quiet && sc->model == PD_MODEL_VES)
        fprintf(stderr,
                PROG ": model ves (Mitchell SAND2011-8064, as LAMMPS peri/ves): K %g Pa, G %g "
                     "Pa, influence %s, lambda %g, tau %g s; contact stiffness from c = "
                     "18K/(pi delta^4)\n",
                sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence),
                sc->ves_lambda, sc->ves_tau);
    if (!o.quiet && sc->model == PD_MODEL_EPS)
        fprintf(stderr,
                PROG ": model eps (Mitchell SAND2011-3166, a corrected plastic update; see "
                     "pd-run(1)): K %g Pa, G %g Pa, influence %s, yield stress %g Pa; contact "
                     "stiffness from c = 18K/(pi delta^4)\n",
                sc->bulk_modulus, sc->shear_modulus, pd_influence_name(sc->influence),
                sc->yield_stress);
    if (!o.quiet && sc->has_projectile && !restart)
        fprintf(stderr,
                PROG ": projectile: mass %g kg, radius %g m, stiffness K %.6g N/m^5%s\n",
                sc->proj_mass, sc->proj_radius, sc->proj_k,
                o.has_proj_k ? "" : " (default: 2 K p = the largest bond stiffness sum of "
                                    "seed 004 eq. 46 at p = spacing/4)");
    if (!o.quiet && restart)
        fprintf(stderr, PROG ": going on from step %lld of '%s'\n", (long long)first, o.restart);

    double t_output = 0, t_start = pd_wtime(), t_shown = 0;
    if (!restart) {
        s = pd_sim_setup(sim);
        if (s == PD_OK && sc->every > 0)
            s = write_frame(out, p, b, sim, o.sc.fields, &t_output, NULL);
    }
    int64_t lost = pd_sim_lost(sim);
    for (int64_t n = first + 1; n <= sc->steps && s == PD_OK; n++) {
        s = pd_sim_step(sim);
        if (s != PD_OK)
            break;
        if (lost == 0 && pd_sim_lost(sim) > 0 && !o.quiet) /* the first; then counts */
            fprintf(stderr,
                    "%s" PROG ": step %lld: %lld particles lost (farther than %g m outside the "
                    "body's box): their bonds broken, at rest from now on\n",
                    tty ? "\r\033[K" : "", (long long)n, (long long)pd_sim_lost(sim),
                    sc->lost_margin);
        lost = pd_sim_lost(sim);
        /* a frame first, so that a status line of the same step takes its
         * energies instead of another pass over the bonds */
        pd_energy e;
        int known = 0;
        if ((sc->every > 0 && n % sc->every == 0) || n == sc->steps) {
            s = write_frame(out, p, b, sim, o.sc.fields, &t_output, &e);
            known = s == PD_OK;
        }
        if (((n - first) % status_every == 0 || n == sc->steps) && !o.quiet) {
            double t0 = pd_wtime(); /* its energy pass is output's time */
            status_line(sim, sc->steps, tty, known ? &e : NULL);
            t_output += pd_wtime() - t0;
        }
        if (tty) {
            double now = pd_wtime();
            if (now - t_shown > 0.2 || n == sc->steps) {
                progress(n - first, nsteps, now - t_start);
                t_shown = now;
            }
        }
    }
    if (s == PD_OK && !restart && sc->steps == 0 && sc->every == 0)
        s = write_frame(out, p, b, sim, o.sc.fields, &t_output, NULL);
    double wall = pd_wtime() - t_start;
    if (tty)
        fputc('\n', stderr);
    if (s == PD_OK) {
        s = pd_file_close(out);
    } else if (s == PD_ERR_UNSTABLE) {
        /* a run that went non-finite keeps the frames written before */
        pd_status c = pd_file_close(out);
        if (c != PD_OK)
            s = c;
    } else
        pd_file_abort(out);
    h.in = h.out = NULL;
    if (s == PD_OK && !o.quiet)
        fprintf(stderr, PROG ": %lld steps in %.3f s (%.3g bond updates/s), contact list builds %lld\n",
                (long long)nsteps, wall,
                wall > 0 ? (double)b->count * (double)nsteps / wall : 0.0,
                (long long)pd_sim_contact_builds(sim));
    if (s == PD_OK && o.timing)
        print_timing(sim, wall, t_output);
    release(&h);
    return s == PD_OK ? 0 : fail();
}

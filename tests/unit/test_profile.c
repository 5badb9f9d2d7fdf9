/*
 * test_profile.c -- profiles of time (lib/base/profile.c): values, exact
 * integrals and rates against hand-computed ones for each form, the
 * resolved text read back to the same numbers, and bad forms refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

static int near(double a, double b)
{
    return fabs(a - b) <= 1e-12 * fmax(1.0, fmax(fabs(a), fabs(b)));
}

static pd_profile parse(const char *spec)
{
    pd_profile g;
    if (pd_profile_parse(spec, &g) != PD_OK)
        die(spec);
    return g;
}

static void constant(void)
{
    int before = failures;
    pd_profile g = parse("2.5");
    CHECK(near(pd_profile_value(&g, 3.0), 2.5), "value");
    CHECK(near(pd_profile_integral(&g, 4.0), 10.0), "integral %g", pd_profile_integral(&g, 4.0));
    CHECK(pd_profile_rate(&g, 1.0) == 0.0, "rate");
    pd_profile_free(&g);
    proved(before, "a constant: g = V, G = V t, g' = 0");
}

static void points(void)
{
    int before = failures;
    /* (1, 2), (3, 6), (4, 0): held at 2 before t = 1, at 0 after t = 4 */
    pd_profile g = parse("points:1,2,3,6,4,0");
    CHECK(near(pd_profile_value(&g, 0.5), 2), "before");
    CHECK(near(pd_profile_value(&g, 2), 4), "inside %g", pd_profile_value(&g, 2));
    CHECK(near(pd_profile_value(&g, 3.5), 3), "inside");
    CHECK(near(pd_profile_value(&g, 9), 0), "after");
    /* G(t) = int_0^t: 2 on [0,1]; then 2 + (t-1)(2 + g(t))/2 */
    CHECK(near(pd_profile_integral(&g, 0.5), 1.0), "G(0.5)");
    CHECK(near(pd_profile_integral(&g, 2), 2 + 3), "G(2) %g", pd_profile_integral(&g, 2));
    CHECK(near(pd_profile_integral(&g, 3), 2 + 8), "G(3)");
    CHECK(near(pd_profile_integral(&g, 4), 2 + 8 + 3), "G(4)");
    CHECK(near(pd_profile_integral(&g, 7), 13), "G(7)");
    CHECK(near(pd_profile_rate(&g, 2), 2) && near(pd_profile_rate(&g, 3.5), -6) &&
              pd_profile_rate(&g, 0.5) == 0 && pd_profile_rate(&g, 5) == 0,
          "rates");
    CHECK(near(pd_profile_rate(&g, 3), -6), "right derivative at a corner");
    pd_profile_free(&g);
    /* a first time after 0: G(t) still starts at 0 */
    g = parse("points:-1,0,1,2");
    CHECK(near(pd_profile_value(&g, 0), 1), "g(0)");
    CHECK(near(pd_profile_integral(&g, 1), 1.5), "G(1) %g", pd_profile_integral(&g, 1));
    CHECK(near(pd_profile_integral(&g, 3), 5.5), "G(3)");
    pd_profile_free(&g);
    proved(before, "points: piecewise linear, held outside, exact integral from 0");
}

static void table(void)
{
    int before = failures;
    char path[] = "/tmp/pd-profile-XXXXXX";
    int fd = mkstemp(path);
    FILE *fp = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (fp == NULL)
        die("mkstemp");
    fprintf(fp, "# time value\n\n1 2   # first\n3\t6\n 4 0\n");
    fclose(fp);
    char spec[64];
    snprintf(spec, sizeof spec, "table:%s", path);
    pd_profile g = parse(spec), h = parse("points:1,2,3,6,4,0");
    for (double t = -1; t < 6; t += 0.25)
        CHECK(pd_profile_value(&g, t) == pd_profile_value(&h, t) &&
                  pd_profile_integral(&g, t) == pd_profile_integral(&h, t),
              "table = points at %g", t);
    char *text = pd_profile_text(&g);
    CHECK(text && strcmp(text, "points:1,2,3,6,4,0") == 0, "resolved '%s'", text);
    free(text);
    pd_profile_free(&g);
    pd_profile_free(&h);
    FILE *bad = fopen(path, "w");
    fprintf(bad, "1 2\n1 3\n");
    fclose(bad);
    pd_profile b;
    CHECK(pd_profile_parse(spec, &b) == PD_ERR_INVALID, "times not increasing");
    bad = fopen(path, "w");
    fprintf(bad, "1 2 3\n");
    fclose(bad);
    CHECK(pd_profile_parse(spec, &b) == PD_ERR_INVALID, "three columns");
    remove(path);
    CHECK(pd_profile_parse(spec, &b) == PD_ERR_IO, "unreadable file");
    proved(before, "table:FILE reads as the same points; bad tables refused; missing is IO");
}

static void pulses(void)
{
    int before = failures;
    pd_profile g = parse("pulses:20,5e-6,-20,5e-6");
    CHECK(pd_profile_value(&g, 0) == 20 && pd_profile_value(&g, 4.9e-6) == 20, "first");
    CHECK(pd_profile_value(&g, 5e-6) == -20 && pd_profile_value(&g, 9.9e-6) == -20, "second");
    CHECK(pd_profile_value(&g, 1e-5) == 0 && pd_profile_value(&g, -1) == 0, "outside");
    CHECK(near(pd_profile_integral(&g, 2e-6), 4e-5), "G in the first");
    CHECK(near(pd_profile_integral(&g, 5e-6), 1e-4), "G at the jump");
    CHECK(near(pd_profile_integral(&g, 7e-6), 6e-5), "G in the second");
    CHECK(fabs(pd_profile_integral(&g, 2e-5)) < 1e-18, "G after: back to 0");
    CHECK(pd_profile_rate(&g, 1e-6) == 0, "rate");
    char *text = pd_profile_text(&g);
    pd_profile h = parse(text);
    for (double t = 0; t < 1.2e-5; t += 1e-7)
        CHECK(pd_profile_value(&g, t) == pd_profile_value(&h, t) &&
                  pd_profile_integral(&g, t) == pd_profile_integral(&h, t),
              "reread at %g", t);
    free(text);
    pd_profile_free(&g);
    pd_profile_free(&h);
    proved(before, "pulses: square pulses from t = 0, exact integral, the text reads back");
}

static void refused(void)
{
    int before = failures;
    const char *bad[] = {"", "x", "1,2", "points:", "points:1", "points:1,2,1,3", "points:1,,2,3",
                         "points:1,2,0,3", "pulses:1", "pulses:1,0", "pulses:1,-1", "pulses:1,2,",
                         "table:", "nan", "inf", "square:1,2"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        pd_profile g;
        CHECK(pd_profile_parse(bad[k], &g) == PD_ERR_INVALID, "'%s' accepted", bad[k]);
    }
    proved(before, "malformed profiles are refused (PD_ERR_INVALID)");
}

static void conditions(void)
{
    int before = failures;
    pd_bc bc;
    CHECK(pd_bc_parse(PD_BC_VELOCITY, "top,y,pulses:20,5e-6,-20,5e-6", &bc) == PD_OK &&
              strcmp(bc.set, "top") == 0 && bc.axis == 1 && bc.profile.kind == PD_PROFILE_PULSES,
          "a velocity condition");
    pd_profile_free(&bc.profile);
    const char *bad[] = {"top", "top,y", "top,y,", "top,w,1", ",y,1", "to p,y,1", "top,yy,1",
                         "top,y,q"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        CHECK(pd_bc_parse(PD_BC_BODY_FORCE, bad[k], &bc) == PD_ERR_INVALID, "'%s'", bad[k]);
    proved(before, "SET,AXIS,PROFILE parses, malformed conditions are refused");
}

int main(void)
{
    constant();
    points();
    table();
    pulses();
    refused();
    conditions();
    return failures != 0;
}

/*
 * model.c -- the table of the material models.  A model is one descriptor
 * (struct pd_model, lib/models/model.h) in its own file; adding one means
 * that file and an entry here.
 */
#include <string.h>

#include "models/model.h"

static const pd_model *const table[] = {&pd_model_pmb, &pd_model_lps, &pd_model_ves,
                                        &pd_model_eps, NULL};

const pd_model *pd_model_at(int k)
{
    return k >= 0 && k < (int)(sizeof table / sizeof table[0]) ? table[k] : NULL;
}

const pd_model *pd_model_by_name(const char *name)
{
    for (int k = 0; table[k]; k++)
        if (strcmp(table[k]->name, name) == 0)
            return table[k];
    return NULL;
}

const pd_model *pd_model_of(pd_model_kind kind)
{
    for (int k = 0; table[k]; k++)
        if (table[k]->kind == kind)
            return table[k];
    return NULL;
}

const char *pd_model_name(const pd_model *m)
{
    return m->name;
}

pd_model_kind pd_model_kind_of(const pd_model *m)
{
    return m->kind;
}

int pd_model_state_based(const pd_model *m)
{
    return m->state_based;
}

int pd_model_history_width(const pd_model *m)
{
    return m->history_width;
}

int pd_model_describe(const pd_model *m, const pd_scene *s, char *text, size_t len)
{
    if (m->describe == NULL || len == 0)
        return 0;
    m->describe(s, text, len);
    return 1;
}

double pd_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s)
{
    return pd_model_of(s->model)->stable_dt(p, b, s);
}

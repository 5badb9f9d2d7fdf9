/*
 * pending.h -- internal (lib/io/pending.c): an output published whole, and
 * XML attribute text.
 */
#ifndef PD_PENDING_H
#define PD_PENDING_H

#include <stdio.h>

#include "pd.h"

/* An output being written: the stream, its temporary path and the target. */
typedef struct {
    FILE *fp;
    char *tmp;
    const char *path;
} pd_pending;

/* Open a new temporary file beside `path`.  It is created with mode 0666 so
 * that the umask, not mkstemp's 0600, decides who may read the result. */
pd_status pd_pending_open(const char *path, pd_pending *out);
/* Finish: when `s` is PD_OK flush, sync and rename over the target;
 * otherwise (or when that fails) remove the temporary.  Returns the status. */
pd_status pd_pending_close(pd_pending *w, pd_status s);
/* A string as the text of an XML attribute value. */
void pd_xml_escaped(FILE *fp, const char *s);

#endif

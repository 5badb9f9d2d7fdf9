/*
 * error.c -- the library's error channel: a status and a one-line message
 * per thread.  Library code never prints; cmd/ prints pd_errmsg().
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <hdf5.h>

#include "pd.h"

static _Thread_local char message[512];

const char *pd_errmsg(void)
{
    return message[0] ? message : "unknown error";
}

pd_status pd_fail(pd_status st, const char *fmt, ...)
{
    /* through a copy: the arguments may hold pd_errmsg() itself (a message
     * wrapped with the file's name), which vsnprintf must not overwrite */
    char buf[sizeof message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    memcpy(message, buf, sizeof message);
    return st;
}

void pd_h5_debug(int on)
{
    /* No HDF5 clean-up at exit: after a failed write (a full disk) HDF5
     * cannot close the file, and its exit handler would crash trying again;
     * pd closes or abandons every file itself.  Only effective before the
     * library's first use, which is why every program calls this first. */
    static int once;
    if (!once) {
        H5dont_atexit();
        once = 1;
    }
    if (on)
        H5Eset_auto2(H5E_DEFAULT, (H5E_auto2_t)H5Eprint2, stderr);
    else
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

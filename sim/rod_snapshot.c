/* rod_snapshot.c: saving and restoring a rod state with its frames (see rod_snapshot.h). */
#include "rod_snapshot.h"

#include <stdlib.h>
#include <string.h>

int rod_snapshot_alloc(const rod *r, rod_snapshot *s)
{
    memset(s, 0, sizeof *s);
    s->ndof = r->ndof;
    s->n = r->n;
    s->q = malloc(sizeof(double) * (size_t)r->ndof);
    s->d1 = malloc(sizeof(double[3]) * (size_t)r->n);
    s->d2 = malloc(sizeof(double[3]) * (size_t)r->n);
    s->tref = malloc(sizeof(double[3]) * (size_t)r->n);
    s->mref = malloc(sizeof(double) * (size_t)r->n);
    if (!s->q || !s->d1 || !s->d2 || !s->tref || !s->mref) {
        rod_snapshot_free(s);
        return 0;
    }
    return 1;
}

void rod_snapshot_free(rod_snapshot *s)
{
    free(s->q); free(s->d1); free(s->d2); free(s->tref); free(s->mref);
    memset(s, 0, sizeof *s);
}

static void copy_parts(double *q, double (*d1)[3], double (*d2)[3], double (*tref)[3], double *mref,
                       const double *fq, double (*fd1)[3], double (*fd2)[3], double (*ftref)[3],
                       const double *fmref, int ndof, int n)
{
    memcpy(q, fq, sizeof(double) * (size_t)ndof);
    memcpy(d1, fd1, sizeof(double[3]) * (size_t)n);
    memcpy(d2, fd2, sizeof(double[3]) * (size_t)n);
    memcpy(tref, ftref, sizeof(double[3]) * (size_t)n);
    memcpy(mref, fmref, sizeof(double) * (size_t)n);
}

void rod_snapshot_save(const rod *r, rod_snapshot *s)
{
    copy_parts(s->q, s->d1, s->d2, s->tref, s->mref, r->q, r->d1, r->d2, r->tref, r->mref, r->ndof, r->n);
}

void rod_snapshot_load(rod *r, const rod_snapshot *s)
{
    copy_parts(r->q, r->d1, r->d2, r->tref, r->mref, s->q, s->d1, s->d2, s->tref, s->mref, r->ndof, r->n);
}

void rod_snapshot_copy(const rod_snapshot *from, rod_snapshot *to)
{
    copy_parts(to->q, to->d1, to->d2, to->tref, to->mref, from->q, from->d1, from->d2, from->tref, from->mref,
               from->ndof, from->n);
}

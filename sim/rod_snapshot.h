/* rod_snapshot.h: a saved rod state (DOFs, reference frames, reference twist), so a path
 * follower can return to any accepted point, not only to the solver's two slots. The frames
 * are part of the state: the energy at q depends on the frames it was transported from. */
#ifndef RIBBON_SIM_ROD_SNAPSHOT_H
#define RIBBON_SIM_ROD_SNAPSHOT_H

#include "rod.h"

typedef struct rod_snapshot {
    int ndof, n;
    double *q, (*d1)[3], (*d2)[3], (*tref)[3], *mref;
} rod_snapshot;

/* Allocates storage for states of r (zeroed struct on failure, returns 0 then). */
int rod_snapshot_alloc(const rod *r, rod_snapshot *s);
void rod_snapshot_free(rod_snapshot *s);
void rod_snapshot_save(const rod *r, rod_snapshot *s);
void rod_snapshot_load(rod *r, const rod_snapshot *s);
void rod_snapshot_copy(const rod_snapshot *from, rod_snapshot *to);

#endif

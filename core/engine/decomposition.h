/* The engine's side of a run across ranks: binds the decomposition library
 * (core/ranks/) to the simulation. */
#ifndef SLUICE_DECOMPOSITION_H
#define SLUICE_DECOMPOSITION_H

#include "sim_internal.h"

#ifdef SLUICE_MPI
/* Sets the halo's width and columns from the scene's components, then
 * splits the particles into the ranks' boxes (sluice_ranks_split) and keeps
 * this rank's. Fails with the message in the simulation's failure.
 * Collective. */
int sluice_sim_split_ranks(sluice_sim *sim);
#endif

#endif

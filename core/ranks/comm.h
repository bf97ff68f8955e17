/* The ranks of a distributed run (docs/scaling.md): MPI when Sluice is built
 * with -Dmpi=enabled, otherwise one rank, and every call below is an inline
 * no-op that the compiler removes (no MPI cost). */
#ifndef SLUICE_COMM_H
#define SLUICE_COMM_H

#include <stddef.h>
#include <stdint.h>

#ifdef SLUICE_MPI
#include <mpi.h>
#endif

typedef struct sluice_comm {
    int rank, size;
#ifdef SLUICE_MPI
    MPI_Comm comm; /* MPI_COMM_NULL: one rank without MPI */
#endif
} sluice_comm;

/* One rank on its own (the default of every simulation). */
static inline sluice_comm sluice_comm_self(void)
{
    sluice_comm c;
    c.rank = 0;
    c.size = 1;
#ifdef SLUICE_MPI
    c.comm = MPI_COMM_NULL;
#endif
    return c;
}

#ifdef SLUICE_MPI
/* The ranks of an MPI communicator (duplicated, so that Sluice's messages
 * never mix with the caller's). 0, or -1 when MPI fails. */
int sluice_comm_from_mpi(sluice_comm *c, MPI_Comm comm);
void sluice_comm_free(sluice_comm *c);
double sluice_comm_min(const sluice_comm *c, double value);
double sluice_comm_max(const sluice_comm *c, double value);
double sluice_comm_sum(const sluice_comm *c, double value);
uint64_t sluice_comm_sum_u64(const sluice_comm *c, uint64_t value);
/* 1 when value is nonzero on any rank */
int sluice_comm_any(const sluice_comm *c, int value);
/* values[0 .. count) combined over the ranks in place; op: a
 * sluice_reduce_op (SLUICE_REDUCE_SUM, _MIN, _MAX). 0, or -1 when MPI fails. */
int sluice_comm_reduce(const sluice_comm *c, double *values, uint32_t count, int op);
/* The sum of count over the ranks before this one, and over all. */
int sluice_comm_offset(const sluice_comm *c, uint64_t count, uint64_t *offset, uint64_t *total);
#else
static inline void sluice_comm_free(sluice_comm *c) { (void)c; }
static inline double sluice_comm_min(const sluice_comm *c, double v) { (void)c; return v; }
static inline double sluice_comm_max(const sluice_comm *c, double v) { (void)c; return v; }
static inline double sluice_comm_sum(const sluice_comm *c, double v) { (void)c; return v; }
static inline uint64_t sluice_comm_sum_u64(const sluice_comm *c, uint64_t v) { (void)c; return v; }
static inline int sluice_comm_any(const sluice_comm *c, int v) { (void)c; return v != 0; }
static inline int sluice_comm_reduce(const sluice_comm *c, double *values, uint32_t count, int op)
{
    (void)c, (void)values, (void)count, (void)op;
    return 0;
}
static inline int sluice_comm_offset(const sluice_comm *c, uint64_t count, uint64_t *offset,
                                     uint64_t *total)
{
    (void)c;
    *offset = 0;
    *total = count;
    return 0;
}
#endif

#endif

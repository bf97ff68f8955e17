#include "comm.h"

#include "sluice/plugin.h"

#ifdef SLUICE_MPI

int sluice_comm_from_mpi(sluice_comm *c, MPI_Comm comm)
{
    *c = sluice_comm_self();
    if (comm == MPI_COMM_NULL)
        return 0;
    if (MPI_Comm_dup(comm, &c->comm) != MPI_SUCCESS)
        return -1;
    if (MPI_Comm_rank(c->comm, &c->rank) != MPI_SUCCESS ||
        MPI_Comm_size(c->comm, &c->size) != MPI_SUCCESS) {
        MPI_Comm_free(&c->comm);
        *c = sluice_comm_self();
        return -1;
    }
    return 0;
}

void sluice_comm_free(sluice_comm *c)
{
    if (c->comm != MPI_COMM_NULL)
        MPI_Comm_free(&c->comm);
    *c = sluice_comm_self();
}

static double reduce(const sluice_comm *c, double value, MPI_Op op)
{
    if (c->size == 1)
        return value;
    double out = value;
    MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, op, c->comm);
    return out;
}

double sluice_comm_min(const sluice_comm *c, double value)
{
    return reduce(c, value, MPI_MIN);
}

double sluice_comm_max(const sluice_comm *c, double value)
{
    return reduce(c, value, MPI_MAX);
}

double sluice_comm_sum(const sluice_comm *c, double value)
{
    return reduce(c, value, MPI_SUM);
}

uint64_t sluice_comm_sum_u64(const sluice_comm *c, uint64_t value)
{
    if (c->size == 1)
        return value;
    uint64_t out = value;
    MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_SUM, c->comm);
    return out;
}

int sluice_comm_any(const sluice_comm *c, int value)
{
    if (c->size == 1)
        return value != 0;
    int in = value != 0, out = in;
    MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, c->comm);
    return out;
}

int sluice_comm_reduce(const sluice_comm *c, double *values, uint32_t count, int op)
{
    if (c->size == 1 || count == 0)
        return 0;
    MPI_Op mpi_op = op == SLUICE_REDUCE_MIN ? MPI_MIN : op == SLUICE_REDUCE_MAX ? MPI_MAX : MPI_SUM;
    return MPI_Allreduce(MPI_IN_PLACE, values, (int)count, MPI_DOUBLE, mpi_op, c->comm) ==
                   MPI_SUCCESS
               ? 0
               : -1;
}

int sluice_comm_offset(const sluice_comm *c, uint64_t count, uint64_t *offset, uint64_t *total)
{
    *offset = 0;
    *total = count;
    if (c->size == 1)
        return 0;
    uint64_t before = 0;
    if (MPI_Exscan(&count, &before, 1, MPI_UINT64_T, MPI_SUM, c->comm) != MPI_SUCCESS ||
        MPI_Allreduce(&count, total, 1, MPI_UINT64_T, MPI_SUM, c->comm) != MPI_SUCCESS)
        return -1;
    *offset = c->rank == 0 ? 0 : before; /* MPI_Exscan leaves rank 0's undefined */
    return 0;
}

#else
/* ISO C forbids an empty translation unit */
typedef int sluice_comm_unused;
#endif

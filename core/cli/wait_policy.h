/* The OpenMP wait policy of a run (wait_policy.c). */
#ifndef SLUICE_WAIT_POLICY_H
#define SLUICE_WAIT_POLICY_H

/* Before anything else in main: when the environment sets no wait policy
 * and other work keeps the processors busy, runs this program again with
 * OMP_WAIT_POLICY=passive. Returns (having changed nothing) otherwise. */
void sluice_cli_set_wait_policy(int argc, char **argv);

#endif

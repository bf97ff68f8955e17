/* Provenance of a run: what produced it (version, git revision, build,
 * command line, date, host) and its kernel, by name, for run.json and for
 * writers through api->output->describe_run. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "build_config.h"
#include "git_revision.h"
#include "sim_internal.h"

int sluice_sim_set_command_line(sluice_sim *sim, const char *command_line)
{
    char *copy = strdup(command_line ? command_line : "");
    if (!copy)
        return -1;
    free(sim->command_line);
    sim->command_line = copy;
    return 0;
}

void sluice_utc_timestamp(char *buffer, size_t size)
{
    time_t now = time(NULL);
    struct tm utc;
    if (now == (time_t)-1 || !gmtime_r(&now, &utc) ||
        strftime(buffer, size, "%Y-%m-%dT%H:%M:%SZ", &utc) == 0)
        snprintf(buffer, size, "unknown");
}

/* The start date and host, taken once, at the first question. */
static void take_date_and_host(sluice_sim *sim)
{
    if (sim->start_date[0])
        return;
    sluice_utc_timestamp(sim->start_date, sizeof sim->start_date);
    if (gethostname(sim->host_name, sizeof sim->host_name) != 0 || !sim->host_name[0])
        strcpy(sim->host_name, "unknown");
    sim->host_name[sizeof sim->host_name - 1] = '\0';
}

const char *sluice_sim_describe(sluice_sim *sim, const char *name)
{
    if (strcmp(name, "version") == 0)
        return SLUICE_VERSION;
    if (strcmp(name, "git_revision") == 0)
        return SLUICE_GIT_REVISION;
    if (strcmp(name, "build") == 0)
        return SLUICE_BUILD_DESCRIPTION;
    if (strcmp(name, "command_line") == 0)
        return sim->command_line ? sim->command_line : "";
    if (strcmp(name, "kernel") == 0)
        return sim->kernel >= 0 ? sim->instances[sim->kernel].component->name : "";
    if (strcmp(name, "date") == 0 || strcmp(name, "host") == 0) {
        take_date_and_host(sim);
        return name[0] == 'd' ? sim->start_date : sim->host_name;
    }
    return NULL;
}

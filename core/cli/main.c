/* The sluice command line: run, check, inspect, study, version; `sluice help
 * COMMAND` and `sluice COMMAND --help` print one command's usage. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifdef SLUICE_MPI
#include <mpi.h>
#endif

#include "build_config.h"
#include "diag.h"
#include "output_dir.h"
#include "scene_schema.h"
#include "wait_policy.h"
#include "sim.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage:\n"
            "  sluice run SCENE.yaml --out DIR [--variant NAME] [--remove PATH ...]\n"
            "             [--swap OLD=NEW ...] [--set key=value ...]\n"
            "             [--threads N] [--restart CHECKPOINT.h5 | --overwrite]\n"
            "             [--progress | --no-progress] [--log-every S] [--quiet | --verbose]\n"
            "  sluice check SCENE.yaml [--variant NAME] [--remove PATH ...] [--swap OLD=NEW ...]\n"
            "               [--set key=value ...] [--schedule]\n"
            "  sluice inspect [PLUGIN] [--markdown]\n"
            "  sluice inspect --schema > sluice-scene.schema.json\n"
            "  sluice study STUDY.yaml [--out DIR] [--jobs N] [--dry-run] [--summary]\n"
            "  sluice probe RUN --fields NAME[,...] (--points P | --line A;B --count N | ...)\n"
            "  sluice version\n"
            "  sluice help COMMAND, sluice COMMAND --help: one command's options\n"
            "\n"
            "--set overrides any scene key by its dotted path, e.g. --set time.end=0.2 or\n"
            "--set plugins.tait.speed_of_sound=60. Plugins are searched in the scene's\n"
            "plugin_path, SLUICE_PLUGIN_PATH, then next to the program.\n"
            "--variant applies one of the scene's named variants (its top-level 'variants':\n"
            "keys removed, plugins swapped, keys set); 'sluice check SCENE' lists them.\n"
            "--remove PATH takes a key out (e.g. plugins.xsph); --swap OLD=NEW replaces the\n"
            "plugin OLD by NEW with NEW's defaults, and the walls OLD handled follow it (e.g.\n"
            "--swap dbc=mdbc). After the variant: the removals, the swaps, then the --set.\n"
            "--schedule prints the evaluation schedule: prepare, passes in order, on-demand\n"
            "terms, integrated fields (run.json holds it too).\n"
            "inspect --schema prints a JSON Schema (draft-07) of scene files, with the\n"
            "plugins on the plugin path, for editors (docs/scene-format.md).\n"
            "--restart continues the run of SCENE from a checkpoint (DIR/checkpoint_*.h5,\n"
            "written every checkpoint.interval s and when SIGINT or SIGTERM stops a run).\n"
            "A run refuses an --out that holds another run (--overwrite replaces it) or\n"
            "that another live run writes to (DIR/.sluice.lock).\n"
            "Progress on stderr: on a terminal one line rewritten in place; otherwise (a\n"
            "batch log) a line with a UTC timestamp every --log-every S s of wall time\n"
            "(default 10), at the start and at the end. --progress forces the terminal\n"
            "line, --no-progress drops both. --quiet (-q): only warnings and failures;\n"
            "--verbose (-v): also the run's provenance and every plugin loaded.\n"
            "Exit status: 0 success, 2 bad input, 3 the run went unstable, 4 other failure (out\n"
            "of memory, a failed write),\n"
            "5 stopped by SIGINT/SIGTERM after a whole step (a checkpoint was written).\n");
}

/* Each command's usage (`sluice COMMAND --help`, `sluice help COMMAND`): the
 * options its parser takes (tests/core/cli/test_help.c holds them to it).
 * `sluice study --help` and `sluice probe --help` are their tools' own. */
static const struct command_usage {
    const char *name, *text;
} command_usages[] = {
    {"run",
     "usage: sluice run SCENE.yaml --out DIR [OPTIONS]\n"
     "Runs the scene and writes its outputs into DIR: scene.resolved.yaml, HDF5 snapshots\n"
     "with an XDMF index, gauge CSV files, checkpoints and run.json.\n"
     "  -o, --out DIR            the output directory (required); one that holds another\n"
     "                           run is refused, as is one that a live run writes to\n"
     "                           (DIR/.sluice.lock)\n"
     "  --overwrite              replace the run in DIR\n"
     "  --restart CHECKPOINT.h5  continue the scene's run from a checkpoint\n"
     "                           (DIR/checkpoint_*.h5)\n"
     "  --variant NAME           apply one of the scene's named variants\n"
     "                           ('sluice check SCENE' lists them)\n"
     "  --remove PATH            take a key out, e.g. plugins.xsph (repeatable)\n"
     "  --swap OLD=NEW           replace the plugin OLD by NEW with NEW's defaults; the\n"
     "                           walls OLD handled follow it, e.g. dbc=mdbc (repeatable)\n"
     "  -s, --set KEY=VALUE      set a scene key by its dotted path, e.g. time.end=0.2 or\n"
     "                           plugins.tait.speed_of_sound=60 (repeatable)\n"
     "  -j, --threads N          OpenMP threads (at most 16 per processor)\n"
     "  --progress, --no-progress\n"
     "                           progress on stderr is one line rewritten in place on a\n"
     "                           terminal, else (a batch log) a line with a UTC timestamp\n"
     "                           at the start, every --log-every S and at the end;\n"
     "                           --progress forces the terminal's line, --no-progress\n"
     "                           drops both\n"
     "  --log-every S            seconds of wall time between a batch log's lines\n"
     "                           (default 10)\n"
     "  -q, --quiet              only warnings and failures\n"
     "  -v, --verbose            also the run's provenance and every plugin loaded\n"
     "  -h, --help               this text\n"
     "After the variant come the removals, the swaps, then the --set. Plugins are searched\n"
     "in the scene's plugin_path, SLUICE_PLUGIN_PATH, then next to the program (the build\n"
     "tree's plugins/, an install's lib/.../sluice/plugins).\n"
     "Exit status: 0 success, 2 bad input, 3 the run went unstable, 4 other failure (out\n"
     "of memory, a failed write), 5 stopped by SIGINT/SIGTERM after a whole step (a\n"
     "checkpoint was written: continue with --restart).\n"},
    {"check",
     "usage: sluice check SCENE.yaml [OPTIONS]\n"
     "Validates the scene without running it: its particle counts, end time, plugin\n"
     "instances and variants.\n"
     "  --schedule               also print the evaluation schedule: prepare, passes in\n"
     "                           order, on-demand terms, integrated fields\n"
     "  --variant NAME           check one of the scene's named variants\n"
     "  --remove PATH            take a key out, e.g. plugins.xsph (repeatable)\n"
     "  --swap OLD=NEW           replace the plugin OLD by NEW with NEW's defaults\n"
     "  -s, --set KEY=VALUE      set a scene key by its dotted path (repeatable)\n"
     "  -j, --threads N          OpenMP threads for filling the scene\n"
     "  -q, --quiet              no plugin notes while the scene loads\n"
     "  -v, --verbose            accepted as for run (a check prints the same)\n"
     "  -h, --help               this text\n"
     "Exit status: 0 valid, 2 bad input (one file:line:column message per problem), 4\n"
     "other failure.\n"},
    {"inspect",
     "usage: sluice inspect [PLUGIN] [--markdown]\n"
     "       sluice inspect --schema > sluice-scene.schema.json\n"
     "Lists the plugins found on the search path (SLUICE_PLUGIN_PATH, then next to the\n"
     "program), or one plugin's components, parameters and fields.\n"
     "  --markdown               the reference as Markdown (docs/plugins.md)\n"
     "  --schema                 a JSON Schema (draft-07) of scene files, with the plugins\n"
     "                           on the plugin path, for editors (docs/scene-format.md)\n"
     "  -h, --help               this text\n"},
    {"version",
     "usage: sluice version\n"
     "Prints the program's version and the plugin ABI it loads.\n"
     "  -h, --help               this text\n"},
};

static const char *command_usage(const char *name)
{
    for (size_t i = 0; i < sizeof command_usages / sizeof *command_usages; i++)
        if (strcmp(command_usages[i].name, name) == 0)
            return command_usages[i].text;
    return NULL;
}

/* -h or --help among a command's arguments */
static int asks_for_help(int argc, char **argv)
{
    for (int i = 2; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    return 0;
}

typedef struct arguments {
    const char *scene, *out, *plugin, *restart, *variant;
    const char **sets, **removals, **swaps;
    size_t set_count, removal_count, swap_count;
    int threads, progress, quiet, verbose, markdown, schedule, overwrite;
    double log_every;
} arguments;

static void free_arguments(arguments *a)
{
    free(a->sets);
    free(a->removals);
    free(a->swaps);
}

static int parse(int argc, char **argv, int first, arguments *a, int allow_out)
{
    a->sets = calloc((size_t)argc + 1, sizeof *a->sets);
    a->removals = calloc((size_t)argc + 1, sizeof *a->removals);
    a->swaps = calloc((size_t)argc + 1, sizeof *a->swaps);
    if (!a->sets || !a->removals || !a->swaps) {
        fprintf(stderr, "sluice: error: out of memory\n");
        return -1;
    }
    a->progress = -1;
    for (int i = first; i < argc; i++) {
        const char *arg = argv[i];
        if (strcmp(arg, "--set") == 0 || strcmp(arg, "-s") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sluice: error: --set needs an argument key=value\n");
                return -1;
            }
            a->sets[a->set_count++] = argv[++i];
        } else if (strncmp(arg, "--set=", 6) == 0) {
            a->sets[a->set_count++] = arg + 6;
        } else if (strcmp(arg, "--remove") == 0 || strncmp(arg, "--remove=", 9) == 0) {
            const char *path = arg[8] == '=' ? arg + 9 : i + 1 < argc ? argv[++i] : NULL;
            if (!path || !*path) {
                fprintf(stderr, "sluice: error: --remove needs a dotted path, e.g. "
                                "plugins.xsph\n");
                return -1;
            }
            a->removals[a->removal_count++] = path;
        } else if (strcmp(arg, "--swap") == 0 || strncmp(arg, "--swap=", 7) == 0) {
            const char *swap = arg[6] == '=' ? arg + 7 : i + 1 < argc ? argv[++i] : NULL;
            if (!swap || !*swap) {
                fprintf(stderr, "sluice: error: --swap needs OLD=NEW, e.g. dbc=mdbc\n");
                return -1;
            }
            a->swaps[a->swap_count++] = swap;
        } else if (strcmp(arg, "--variant") == 0 || strncmp(arg, "--variant=", 10) == 0) {
            const char *name = arg[9] == '=' ? arg + 10 : i + 1 < argc ? argv[++i] : NULL;
            if (!name || !*name) {
                fprintf(stderr, "sluice: error: --variant needs the name of one of the scene's "
                                "variants\n");
                return -1;
            }
            if (a->variant) {
                fprintf(stderr, "sluice: error: --variant is given twice ('%s' and '%s'); a run "
                                "applies at most one variant\n",
                        a->variant, name);
                return -1;
            }
            a->variant = name;
        } else if (allow_out && (strcmp(arg, "--out") == 0 || strcmp(arg, "-o") == 0)) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sluice: error: --out needs a directory\n");
                return -1;
            }
            a->out = argv[++i];
        } else if (allow_out && strncmp(arg, "--out=", 6) == 0) {
            a->out = arg + 6;
        } else if (allow_out && strcmp(arg, "--restart") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sluice: error: --restart needs a checkpoint file\n");
                return -1;
            }
            a->restart = argv[++i];
        } else if (allow_out && strncmp(arg, "--restart=", 10) == 0) {
            a->restart = arg + 10;
        } else if (allow_out && strcmp(arg, "--overwrite") == 0) {
            a->overwrite = 1;
        } else if (strcmp(arg, "--threads") == 0 || strcmp(arg, "-j") == 0) {
            char *end = NULL;
            long threads = 0;
            if (i + 1 >= argc || (threads = strtol(argv[i + 1], &end, 10), *end) || threads < 1) {
                fprintf(stderr, "sluice: error: --threads needs a positive integer\n");
                return -1;
            }
            /* more threads than 16 per processor only compete (and libgomp
             * crashes creating tens of thousands) */
            long cpus = sysconf(_SC_NPROCESSORS_ONLN);
            long most = 16 * (cpus > 0 ? cpus : 1);
            if (threads > most) {
                fprintf(stderr,
                        "sluice: error: --threads %s: at most %ld, 16 per processor (this "
                        "machine has %ld)\n",
                        argv[i + 1], most, cpus > 0 ? cpus : 1);
                return -1;
            }
            a->threads = (int)threads;
            i++;
        } else if (allow_out && strcmp(arg, "--progress") == 0) {
            a->progress = 1;
        } else if (allow_out && strcmp(arg, "--no-progress") == 0) {
            a->progress = 0;
        } else if (allow_out && strcmp(arg, "--log-every") == 0) {
            char *end = NULL;
            if (i + 1 >= argc || (a->log_every = strtod(argv[i + 1], &end), *end) ||
                !(a->log_every > 0 && a->log_every < 1e9)) {
                fprintf(stderr, "sluice: error: --log-every needs a positive number of seconds\n");
                return -1;
            }
            i++;
        } else if (strcmp(arg, "--quiet") == 0 || strcmp(arg, "-q") == 0) {
            a->quiet = 1;
        } else if (strcmp(arg, "--verbose") == 0 || strcmp(arg, "-v") == 0) {
            a->verbose = 1;
        } else if (!allow_out && strcmp(arg, "--schedule") == 0) {
            a->schedule = 1;
        } else if (arg[0] == '-' && arg[1]) {
            fprintf(stderr, "sluice: error: unknown option '%s' ('sluice %s --help' lists them)\n",
                    arg, argv[1]);
            return -1;
        } else if (!a->scene) {
            a->scene = arg;
        } else {
            fprintf(stderr, "sluice: error: unexpected argument '%s'\n", arg);
            return -1;
        }
    }
    if (!a->scene) {
        fprintf(stderr, "sluice: error: no scene file given\n");
        return -1;
    }
    if (a->quiet && a->verbose) {
        fprintf(stderr, "sluice: error: give either --quiet or --verbose\n");
        return -1;
    }
    return 0;
}

/* This process's rank in a run across MPI ranks (docs/scaling.md), 0 otherwise.
 * Messages every rank would print alike are printed by rank 0. */
static int world_rank(void)
{
#ifdef SLUICE_MPI
    int initialised = 0, rank = 0;
    if (MPI_Initialized(&initialised) == MPI_SUCCESS && initialised)
        MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
#else
    return 0;
#endif
}

/* The scene loaded, or NULL with its messages printed; *resources is set
 * when it failed for want of memory (exit 4) rather than bad input (2). */
static sluice_sim *load(const arguments *a, int check_only, const void *communicator,
                        int *resources)
{
    *resources = 0;
    sluice_diag *diag = sluice_diag_create();
    if (!diag) {
        fprintf(stderr, "sluice: error: out of memory\n");
        return NULL;
    }
    sluice_load_options options = {.overrides = a->sets,
                                   .override_count = a->set_count,
                                   .threads = a->threads,
                                   .check_only = check_only,
                                   .communicator = communicator,
                                   .removals = a->removals,
                                   .removal_count = a->removal_count,
                                   .swaps = a->swaps,
                                   .swap_count = a->swap_count,
                                   .quiet = a->quiet,
                                   /* a run into a batch log: as its progress lines */
                                   .timestamps = !check_only && !a->quiet && a->progress != 0 &&
                                                 a->progress != 1 && !isatty(STDERR_FILENO)};
    sluice_sim *sim = sluice_sim_load_variant(a->scene, a->variant, &options, diag);
    if (world_rank() == 0)
        sluice_diag_print(diag, stderr);
    *resources = !sim && sluice_diag_resources(diag);
    sluice_diag_destroy(diag);
    return sim;
}

/* The command line as a shell would take it back: arguments with anything
 * but letters, digits and -_./=,:+@% in single quotes. NULL out of memory. */
static char *command_line_text(int argc, char **argv)
{
    size_t size = 1;
    for (int i = 0; i < argc; i++)
        size += 4 * strlen(argv[i]) + 3;
    char *text = malloc(size), *out = text;
    if (!text)
        return NULL;
    for (int i = 0; i < argc; i++) {
        const char *arg = argv[i];
        const int plain = arg[0] && strspn(arg, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                "0123456789-_./=,:+@%") == strlen(arg);
        if (i > 0)
            *out++ = ' ';
        if (plain) {
            out = stpcpy(out, arg);
            continue;
        }
        *out++ = '\'';
        for (; *arg; arg++)
            out = *arg == '\'' ? stpcpy(out, "'\\''") : (*out = *arg, out + 1);
        *out++ = '\'';
    }
    *out = '\0';
    return text;
}

/* Before the first step: in a batch log (and with --verbose) a timestamped
 * line saying what runs where; with --verbose the provenance and every
 * plugin loaded. */
static void report_start(sluice_sim *sim, const arguments *a, int progress)
{
    if (a->quiet || (progress != SLUICE_PROGRESS_LOG && !a->verbose))
        return;
    char stamp[40];
    sluice_utc_timestamp(stamp, sizeof stamp);
    fprintf(stderr, "%s sluice: run of %s%s%s on %s, %d threads, output in %s\n", stamp, a->scene,
            a->variant ? " --variant " : "", a->variant ? a->variant : "",
            sluice_sim_describe(sim, "host"), sluice_sim_threads(sim), a->out);
    if (!a->verbose)
        return;
    static const char *const described[] = {"version", "git_revision", "build", "command_line",
                                            "kernel"};
    for (size_t k = 0; k < sizeof described / sizeof *described; k++)
        fprintf(stderr, "sluice: %s: %s\n", described[k], sluice_sim_describe(sim, described[k]));
    const char *component = NULL, *instance;
    for (uint32_t k = 0; (instance = sluice_sim_instance(sim, k, &component)); k++)
        fprintf(stderr, "sluice: plugin %s (%s)\n", instance, component);
    fflush(stderr);
}

static int command_run(int argc, char **argv, int across_ranks)
{
    arguments a;
    memset(&a, 0, sizeof a);
    if (parse(argc, argv, 2, &a, 1) != 0) {
        free_arguments(&a);
        return 2;
    }
    if (!a.out) {
        fprintf(stderr, "sluice: error: 'sluice run' needs --out DIR\n");
        free_arguments(&a);
        return 2;
    }
    if (a.overwrite && a.restart) {
        fprintf(stderr, "sluice: error: give either --overwrite (replace the run in --out) or "
                        "--restart (continue a run)\n");
        free_arguments(&a);
        return 2;
    }
    int resources = 0;
#ifdef SLUICE_MPI
    /* under mpiexec: one run across the ranks of MPI_COMM_WORLD */
    MPI_Comm world = MPI_COMM_WORLD;
    sluice_sim *sim = load(&a, 0, across_ranks ? &world : NULL, &resources);
#else
    (void)across_ranks;
    sluice_sim *sim = load(&a, 0, NULL, &resources);
#endif
    const int quiet_rank = world_rank() != 0;
    free_arguments(&a);
    if (!sim)
        return resources ? 4 : 2;
    char *command_line = command_line_text(argc, argv);
    if (!command_line || sluice_sim_set_command_line(sim, command_line) != 0) {
        free(command_line);
        fprintf(stderr, "sluice: error: out of memory\n");
        sluice_sim_free(sim);
        return 4;
    }
    free(command_line);
    if (a.restart) {
        char error[2048];
        if (sluice_sim_restart(sim, a.restart, error, sizeof error) != 0) {
            if (!quiet_rank)
                fprintf(stderr, "sluice: error: %s\n", error);
            sluice_sim_free(sim);
            return 2;
        }
        if (!a.quiet && !quiet_rank)
            fprintf(stderr, "sluice: restarting from %s at step %lld, t = %.9g s\n", a.restart,
                    (long long)sluice_sim_steps(sim), sluice_sim_time(sim));
    }
    /* the scene and the checkpoint are valid: claim the output directory
     * (rank 0 for all) */
    int lock_fd = -1, claim = SLUICE_OUTPUT_OK;
    char claim_error[4096] = "";
    if (!quiet_rank)
        claim = sluice_output_dir_claim(a.out, a.restart != NULL, a.overwrite, &lock_fd,
                                        claim_error, sizeof claim_error);
#ifdef SLUICE_MPI
    if (across_ranks)
        MPI_Bcast(&claim, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
    if (claim != SLUICE_OUTPUT_OK) {
        if (!quiet_rank)
            fprintf(stderr, "sluice: error: %s\n", claim_error);
        sluice_sim_free(sim);
        return claim == SLUICE_OUTPUT_REFUSED ? 2 : 4;
    }
    if (sluice_install_stop_handlers() != 0 && !quiet_rank)
        fprintf(stderr, "sluice: warning: cannot catch SIGINT/SIGTERM; an interrupted run "
                        "writes no checkpoint\n");
    /* --progress: the terminal line; otherwise the line on a terminal and
     * timestamped lines in a batch log, none with --quiet */
    const int progress = quiet_rank || a.progress == 0 ? SLUICE_PROGRESS_NONE
                         : a.progress == 1             ? SLUICE_PROGRESS_LINE
                         : a.quiet                     ? SLUICE_PROGRESS_NONE
                         : isatty(STDERR_FILENO)       ? SLUICE_PROGRESS_LINE
                                                       : SLUICE_PROGRESS_LOG;
    sluice_run_options options = {a.out, progress, a.quiet || quiet_rank, a.log_every};
    if (!quiet_rank)
        report_start(sim, &a, progress);
    int status = sluice_sim_run(sim, &options);
    char stamp[40] = "";
    if (progress == SLUICE_PROGRESS_LOG) {
        sluice_utc_timestamp(stamp, sizeof stamp - 1);
        strcat(stamp, " ");
    }
    const unsigned long long particles = sluice_sim_particle_total(sim);
    if (quiet_rank) {
        /* a failing step ended every rank with its own message (MPI_Abort) */
    } else if (status == SLUICE_RUN_COMPLETE) {
        if (!a.quiet)
            fprintf(stderr, "%ssluice: completed %lld steps, %.6g s simulated, %llu particles; output "
                            "in %s\n",
                    stamp, (long long)sluice_sim_steps(sim), sluice_sim_time(sim), particles, a.out);
    } else if (status == SLUICE_RUN_INTERRUPTED) {
        fprintf(stderr, "%ssluice: stopped by a signal after step %lld, t = %.9g s; continue with "
                        "--restart %s/checkpoint_%09lld.h5%s%s\n",
                stamp, (long long)sluice_sim_steps(sim), sluice_sim_time(sim), a.out,
                (long long)sluice_sim_steps(sim), a.variant ? " --variant " : "",
                a.variant ? a.variant : "");
    } else {
        fprintf(stderr, "%ssluice: error: %s\n", stamp, sluice_sim_failure(sim));
        if (status == SLUICE_RUN_UNSTABLE)
            fprintf(stderr,
                    "sluice: the run was stopped; every output written before step %lld is kept "
                    "in %s\n",
                    (long long)sluice_sim_steps(sim), a.out);
    }
    sluice_sim_free(sim);
    if (lock_fd >= 0)
        close(lock_fd);
    return status;
}

static int command_check(int argc, char **argv)
{
    arguments a;
    memset(&a, 0, sizeof a);
    if (parse(argc, argv, 2, &a, 0) != 0) {
        free_arguments(&a);
        return 2;
    }
    int resources = 0;
    sluice_sim *sim = load(&a, 1, NULL, &resources);
    free_arguments(&a);
    if (!sim)
        return resources ? 4 : 2;
    const sluice_view *v = sluice_sim_view(sim);
    sluice_index kinds[SLUICE_KIND_COUNT] = {0};
    for (sluice_index i = 0; i < v->count; i++)
        kinds[v->kind[i] < SLUICE_KIND_COUNT ? v->kind[i] : 0]++;
    char open[64] = "";
    if (kinds[SLUICE_KIND_OPEN])
        snprintf(open, sizeof open, ", %u open-boundary", kinds[SLUICE_KIND_OPEN]);
    char variant[256] = "";
    if (sluice_sim_variant(sim))
        snprintf(variant, sizeof variant, " (variant '%.200s')", sluice_sim_variant(sim));
    printf("%s: valid %uD scene%s, %u particles (%u fluid, %u wall%s), end time %g s\n", a.scene,
           v->dimensions, variant, v->count, kinds[SLUICE_KIND_FLUID], kinds[SLUICE_KIND_WALL],
           open, sluice_sim_end_time(sim));
    /* plugins loaded under instance names */
    const char *instance, *component;
    int listed = 0;
    for (uint32_t k = 0; (instance = sluice_sim_instance(sim, k, &component)); k++)
        if (strcmp(instance, component) != 0)
            printf("%s%s (%s)", listed++ ? ", " : "instances: ", instance, component);
    if (listed)
        printf("\n");
    if (a.schedule)
        sluice_sim_write_schedule(sim, stdout, 0);
    /* the base scene was checked: list its variants */
    if (!sluice_sim_variant(sim) && sluice_sim_scene_variant(sim, 0, NULL)) {
        const char *name, *description;
        int width = 0;
        for (size_t i = 0; (name = sluice_sim_scene_variant(sim, i, NULL)); i++)
            width = (int)strlen(name) > width ? (int)strlen(name) : width;
        printf("variants (sluice check|run SCENE --variant NAME):\n");
        for (size_t i = 0; (name = sluice_sim_scene_variant(sim, i, &description)); i++)
            if (*description)
                printf("  %-*s  %s\n", width, name, description);
            else
                printf("  %s\n", name);
    }
    sluice_sim_free(sim);
    return 0;
}

static int command_inspect(int argc, char **argv)
{
    const char *plugin = NULL;
    int markdown = 0, schema = 0;
    for (int i = 2; i < argc; i++) {
        if (strcmp(argv[i], "--markdown") == 0)
            markdown = 1;
        else if (strcmp(argv[i], "--schema") == 0)
            schema = 1;
        else if (argv[i][0] == '-') {
            fprintf(stderr,
                    "sluice: error: unknown option '%s' ('sluice inspect --help' lists them)\n",
                    argv[i]);
            return 2;
        } else if (!plugin)
            plugin = argv[i];
        else {
            fprintf(stderr, "sluice: error: unexpected argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (schema && (plugin || markdown)) {
        fprintf(stderr, "sluice: error: --schema describes the whole scene format: it takes no "
                        "PLUGIN and no --markdown\n");
        return 2;
    }
    if (schema)
        return sluice_scene_schema(stdout) == 0 ? 0 : 4;
    return sluice_inspect(stdout, plugin, markdown) == 0 ? 0 : 2;
}

/* `sluice study ...` and `sluice probe ...` run the tools sluice-study
 * (tools/study, docs/studies.md) and sluice-probe (tools/probe,
 * docs/probe.md), found next to this program (the build tree's tools/, or an
 * install's bindir), with SLUICE naming this program (the study runs it). */
static int command_tool(char **argv, const char *tool)
{
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) {
        fprintf(stderr, "sluice: error: cannot find this program's directory\n");
        return 4;
    }
    self[n] = '\0';
    setenv("SLUICE", self, 0);
    char *slash = strrchr(self, '/');
    *slash = '\0';
    static const char *const places[] = {"tools/sluice-", "sluice-"};
    for (size_t i = 0; i < 2; i++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s%s", self, places[i], tool);
        if (access(path, X_OK) == 0) {
            argv[1] = path;
            execv(path, argv + 1);
        }
    }
    fprintf(stderr, "sluice: error: the tool sluice-%s is not next to this program "
                    "(%s/tools or %s)\n",
            tool, self, self);
    return 4;
}

/* `sluice help [COMMAND]`: the usage, or one command's. */
static int command_help(int argc, char **argv)
{
    if (argc < 3) {
        usage(stdout);
        return 0;
    }
    if (argc > 3) {
        fprintf(stderr, "sluice: error: 'sluice help' takes one command\n");
        return 2;
    }
    if (strcmp(argv[2], "study") == 0 || strcmp(argv[2], "probe") == 0) {
        char *tool_help[] = {argv[0], argv[2], "--help", NULL};
        return command_tool(tool_help, argv[2]);
    }
    const char *text = command_usage(argv[2]);
    if (!text) {
        fprintf(stderr, "sluice: error: unknown command '%s' ('sluice help' lists them)\n",
                argv[2]);
        return 2;
    }
    fputs(text, stdout);
    return 0;
}

int main(int argc, char **argv)
{
    sluice_cli_set_wait_policy(argc, argv);
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *command = argv[1];
    if (strcmp(command, "help") == 0)
        return command_help(argc, argv);
    /* `sluice COMMAND --help` (sluice-study and sluice-probe answer their own) */
    if (command_usage(command) && asks_for_help(argc, argv)) {
        fputs(command_usage(command), stdout);
        return 0;
    }
    if (strcmp(command, "run") == 0) {
#ifdef SLUICE_MPI
        /* MPI only under a launcher (mpiexec sets these): a plain `sluice
         * run` of the MPI build is one process without MPI, as without it */
        if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMIX_RANK") && !getenv("PMI_SIZE"))
            return command_run(argc, argv, 0);
        int provided = 0;
        if (MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
            fprintf(stderr, "sluice: error: MPI could not start\n");
            return 4;
        }
        int status = command_run(argc, argv, 1);
        MPI_Finalize();
        return status;
#else
        return command_run(argc, argv, 0);
#endif
    }
    if (strcmp(command, "check") == 0)
        return command_check(argc, argv);
    if (strcmp(command, "inspect") == 0)
        return command_inspect(argc, argv);
    if (strcmp(command, "study") == 0 || strcmp(command, "probe") == 0)
        return command_tool(argv, command);
    if (strcmp(command, "version") == 0 || strcmp(command, "--version") == 0) {
        if (argc > 2) {
            fprintf(stderr, "sluice: error: 'sluice version' takes no arguments ('%s')\n",
                    argv[2]);
            return 2;
        }
        printf("sluice %s (plugin ABI %d.%d)\n", SLUICE_VERSION, SLUICE_ABI_MAJOR,
               SLUICE_ABI_MINOR);
        return 0;
    }
    if (strcmp(command, "--help") == 0 || strcmp(command, "-h") == 0) {
        usage(stdout);
        return 0;
    }
    fprintf(stderr, "sluice: error: unknown command '%s' ('sluice help' lists them)\n", command);
    return 2;
}

/* The command lines' help: every command of sluice, sluice-analyze,
 * sluice-study and sluice-probe prints its usage to stdout and exits 0 on
 * --help and -h (and `help COMMAND`), and the usage names every option its
 * parser takes:
 *  - sluice, sluice-study and sluice-probe: each option string of the
 *    program's source (core/cli/main.c, tools/study/main.c,
 *    tools/probe/probe.c) that a command does not refuse as unknown is in
 *    that command's usage, and each option its usage names is taken;
 *  - sluice-analyze: each option of its table is in `sluice-analyze --help`,
 *    each command of its table has a usage of its own that names only options
 *    of the table.
 * An unknown option is one message on stderr and exit status 2. */
#include <ctype.h>

#include "test_util.h"

/* `PROGRAM ARGS` of the build tree; stdout into *output (stderr too with
 * both), the exit status returned. */
static int program(const char *name, const char *args, int both, char **output)
{
    char *command = NULL;
    ck_assert_int_ge(asprintf(&command, "%s/%s %s </dev/null %s", test_build_dir(), name, args,
                              both ? "2>&1" : "2>/dev/null"),
                     0);
    int status = test_popen(command, output);
    free(command);
    return status;
}

/* Whether `text` names `option` as a word of its own (not inside a longer
 * option or word). */
static int names_option(const char *text, const char *option)
{
    const size_t n = strlen(option);
    for (const char *p = strstr(text, option); p; p = strstr(p + 1, option)) {
        const int before = p > text && (isalnum((unsigned char)p[-1]) || p[-1] == '-');
        const int after = isalnum((unsigned char)p[n]) || p[n] == '-';
        if (!before && !after)
            return 1;
    }
    return 0;
}

/* The string literals of a source file that have the form of an option
 * (-x, --name or --name=, the '=' dropped), each once; NULL-terminated. */
static char **source_options(const char *relative)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", test_source_dir(), relative), 0);
    char *text = test_read_file(path);
    ck_assert_msg(text != NULL, "cannot read %s", path);
    free(path);
    size_t count = 0;
    char **options = calloc(strlen(text) / 4 + 1, sizeof *options);
    ck_assert_ptr_nonnull(options);
    for (const char *p = text; *p; p++) {
        if (*p == '\'' && p[1] && p[2] == '\'') { /* a character literal such as '"' */
            p += 2;
            continue;
        }
        if (*p != '"')
            continue;
        const char *start = ++p;
        while (*p && *p != '"')
            p += *p == '\\' && p[1] ? 2 : 1;
        size_t n = (size_t)(p - start);
        if (n > 1 && start[n - 1] == '=')
            n--;
        size_t dashes = n > 2 && start[1] == '-' ? 2 : 1;
        int option = start[0] == '-' && n > dashes && islower((unsigned char)start[dashes]);
        for (size_t i = dashes; option && i < n; i++)
            option = islower((unsigned char)start[i]) || isdigit((unsigned char)start[i]) ||
                     start[i] == '-';
        if (option && !(dashes == 1 && n != 2)) {
            char *name = strndup(start, n);
            int known = 0;
            for (size_t i = 0; i < count && !known; i++)
                known = strcmp(options[i], name) == 0;
            if (known)
                free(name);
            else
                options[count++] = name;
        }
        if (!*p)
            break;
    }
    free(text);
    ck_assert_msg(count > 3, "no options found in %s", relative);
    return options;
}

static void free_list(char **list)
{
    for (size_t i = 0; list[i]; i++)
        free(list[i]);
    free(list);
}

/* The usage of `PROGRAM COMMAND` by --help, -h and `help COMMAND` (the same
 * text, on stdout, exit 0, starting with `usage: SHOWN COMMAND`). */
static char *usage_of(const char *name, const char *shown, const char *command)
{
    char *args = NULL, *text = NULL, *other = NULL, *head = NULL;
    ck_assert_int_ge(asprintf(&args, "%s --help", command), 0);
    ck_assert_msg(program(name, args, 0, &text) == 0, "%s %s: not exit 0", name, args);
    free(args);
    ck_assert_int_ge(asprintf(&head, "usage: %s %s", shown, command), 0);
    ck_assert_msg(strncmp(text, head, strlen(head)) == 0, "%s %s --help begins '%.60s', not '%s'",
                  name, command, text, head);
    free(head);
    const char *forms[] = {"%s -h", "help %s"};
    for (int k = 0; k < 2; k++) {
        ck_assert_int_ge(asprintf(&args, forms[k], command), 0);
        ck_assert_msg(program(name, args, 0, &other) == 0, "%s %s: not exit 0", name, args);
        ck_assert_msg(strcmp(text, other) == 0, "%s %s differs from --help", name, args);
        free(other);
        free(args);
    }
    return text;
}

/* `PROGRAM COMMAND OPTION` alone: whether the parser takes OPTION (any
 * message but that of an unknown option). */
static int takes(const char *name, const char *command, const char *option)
{
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "%s %s", command, option), 0);
    program(name, args, 1, &output);
    int taken =
        strstr(output, "unknown option") == NULL && strstr(output, "takes no arguments") == NULL;
    free(output);
    free(args);
    return taken;
}

/* Each option of the source that COMMAND takes is in its usage; each
 * option its usage names is taken. */
static void check_usage_against_parser(const char *name, const char *command, const char *usage,
                                       char **options)
{
    for (size_t i = 0; options[i]; i++)
        if (takes(name, command, options[i]))
            ck_assert_msg(names_option(usage, options[i]),
                          "%s %s takes %s but its --help does not name it", name, command,
                          options[i]);
    for (const char *p = usage; (p = strchr(p, '-')); p++) {
        if (p > usage && !strchr(" [(,|", p[-1]))
            continue;
        size_t n = strspn(p, "-abcdefghijklmnopqrstuvwxyz0123456789");
        if (n < 2 || (p[1] == '-' && n < 3))
            continue;
        char *option = strndup(p, n);
        ck_assert_msg(takes(name, command, option), "%s %s --help names %s, which it refuses", name,
                      command, option);
        free(option);
    }
}

/* An unknown option: one line (on stderr), exit 2. */
static void check_unknown_option(const char *name, const char *command)
{
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "%s --no-such-option", command), 0);
    ck_assert_int_eq(program(name, args, 1, &output), 2);
    ck_assert_msg(strstr(output, "unknown option"), "%s %s: %s", name, args, output);
    ck_assert_msg(strchr(output, '\n') == output + strlen(output) - 1, "%s %s: not one line: %s",
                  name, args, output);
    free(output);
    free(args);
}

START_TEST(sluice_commands)
{
    char **options = source_options("core/cli/main.c");
    const char *commands[] = {"run", "check", "inspect", "version"}; /* study, probe: below */
    for (size_t k = 0; k < sizeof commands / sizeof *commands; k++) {
        char *usage = usage_of("sluice", "sluice", commands[k]);
        check_usage_against_parser("sluice", commands[k], usage, options);
        free(usage);
    }
    for (size_t k = 0; k < 3; k++)
        check_unknown_option("sluice", commands[k]);
    /* the program's usage lists every command and how to get its usage */
    char *usage = NULL;
    ck_assert_int_eq(program("sluice", "--help", 0, &usage), 0);
    for (size_t k = 0; k < sizeof commands / sizeof *commands; k++)
        ck_assert_msg(names_option(usage, commands[k]), "sluice --help lacks %s", commands[k]);
    ck_assert_ptr_nonnull(strstr(usage, "sluice study"));
    ck_assert_ptr_nonnull(strstr(usage, "sluice probe"));
    ck_assert_ptr_nonnull(strstr(usage, "sluice help COMMAND"));
    free(usage);
    char *output = NULL;
    ck_assert_int_eq(program("sluice", "help no-such-command", 1, &output), 2);
    free(output);
    ck_assert_int_eq(program("sluice", "no-such-command", 1, &output), 2);
    ck_assert_msg(strstr(output, "unknown command") &&
                      strchr(output, '\n') == strrchr(output, '\n'),
                  "sluice no-such-command: %s", output);
    free(output);
    ck_assert_int_eq(program("sluice", "version extra", 1, &output), 2);
    free(output);
    free_list(options);
}
END_TEST

START_TEST(probe_command)
{
    char **options = source_options("tools/probe/probe.c");
    /* sluice probe hands its arguments to sluice-probe: the same usage */
    char *usage = usage_of("sluice", "sluice", "probe");
    char *own = NULL;
    ck_assert_int_eq(program("tools/sluice-probe", "--help", 0, &own), 0);
    ck_assert_str_eq(usage, own);
    check_usage_against_parser("tools/sluice-probe", "", usage, options);
    check_unknown_option("sluice", "probe");
    free(own);
    free(usage);
    free_list(options);
}
END_TEST

START_TEST(study_command)
{
    char **options = source_options("tools/study/main.c");
    /* sluice study hands its arguments to sluice-study: the same usage */
    char *usage = usage_of("sluice", "sluice", "study");
    char *own = NULL;
    ck_assert_int_eq(program("tools/sluice-study", "--help", 0, &own), 0);
    ck_assert_str_eq(usage, own);
    check_usage_against_parser("tools/sluice-study", "", usage, options);
    check_unknown_option("sluice", "study");
    char *output = NULL;
    ck_assert_int_eq(program("tools/sluice-study", "--out", 1, &output), 2);
    ck_assert_msg(strstr(output, "--out needs a value"), "%s", output);
    free(output);
    free(own);
    free(usage);
    free_list(options);
}
END_TEST

/* The names of sluice-analyze's table rows {"NAME", PREFIX...}. */
static char **table_names(const char *text, const char *prefix)
{
    size_t count = 0;
    char **names = calloc(strlen(text) / 8 + 1, sizeof *names);
    ck_assert_ptr_nonnull(names);
    for (const char *p = strstr(text, "{\""); p; p = strstr(p + 2, "{\"")) {
        const char *end = strchr(p + 2, '"');
        if (end && strncmp(end + 1, ", ", 2) == 0 && strncmp(end + 3, prefix, strlen(prefix)) == 0)
            names[count++] = strndup(p + 2, (size_t)(end - p - 2));
    }
    ck_assert_msg(count > 5, "no rows with %s in tools/analyze/main.c", prefix);
    return names;
}

START_TEST(analyze_commands)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/tools/analyze/main.c", test_source_dir()), 0);
    char *source = test_read_file(path);
    ck_assert_ptr_nonnull(source);
    char **options = table_names(source, "OPT_");
    char **commands = table_names(source, "cmd_");
    char *usage = NULL;
    ck_assert_int_eq(program("tools/sluice-analyze", "--help", 0, &usage), 0);
    for (size_t i = 0; options[i]; i++) {
        char *option = NULL;
        ck_assert_int_ge(asprintf(&option, "--%s", options[i]), 0);
        ck_assert_msg(names_option(usage, option), "sluice-analyze --help does not name %s",
                      option);
        free(option);
    }
    for (size_t k = 0; commands[k]; k++) {
        ck_assert_msg(names_option(usage, commands[k]), "sluice-analyze --help lacks %s",
                      commands[k]);
        char *own = usage_of("tools/sluice-analyze", "sluice-analyze", commands[k]);
        /* every option it names is one of the table's */
        for (const char *p = strstr(own, "--"); p; p = strstr(p + 2, "--")) {
            size_t n = strspn(p + 2, "abcdefghijklmnopqrstuvwxyz0123456789-");
            int known = 0;
            for (size_t i = 0; options[i] && !known; i++)
                known = strlen(options[i]) == n && strncmp(options[i], p + 2, n) == 0;
            ck_assert_msg(known, "sluice-analyze %s --help names --%.*s, not an option",
                          commands[k], (int)n, p + 2);
        }
        free(own);
        check_unknown_option("tools/sluice-analyze", commands[k]);
    }
    char *output = NULL;
    ck_assert_int_eq(program("tools/sluice-analyze", "help no-such-command", 1, &output), 2);
    free(output);
    /* an option the command does not read: a warning that it has no effect */
    ck_assert_int_eq(program("tools/sluice-analyze", "belanger --d1 0.02 --v1 1.5 --x 3", 1,
                             &output),
                     0);
    ck_assert_msg(strstr(output, "warning: 'belanger' does not read --x: it has no effect"),
                  "%s", output);
    free(output);
    ck_assert_int_eq(program("tools/sluice-analyze", "belanger --d1 0.02 --v1 1.5", 1, &output),
                     0);
    ck_assert_msg(!strstr(output, "warning"), "%s", output);
    free(output);
    free(usage);
    free_list(options);
    free_list(commands);
    free(source);
    free(path);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("cli help");
    TCase *tc = tcase_create("help");
    tcase_add_test(tc, sluice_commands);
    tcase_add_test(tc, study_command);
    tcase_add_test(tc, probe_command);
    tcase_add_test(tc, analyze_commands);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}

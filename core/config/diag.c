#include "diag.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

struct sluice_diag {
    char **messages;
    sluice_severity *severities;
    size_t count, capacity, errors;
    int resources; /* an error was for want of memory */
};

sluice_diag *sluice_diag_create(void)
{
    return calloc(1, sizeof(sluice_diag));
}

void sluice_diag_clear(sluice_diag *diag)
{
    for (size_t i = 0; i < diag->count; i++)
        free(diag->messages[i]);
    diag->count = 0;
    diag->errors = 0;
}

void sluice_diag_destroy(sluice_diag *diag)
{
    if (!diag)
        return;
    sluice_diag_clear(diag);
    free(diag->messages);
    free(diag->severities);
    free(diag);
}

static char *vformat(const char *format, va_list ap)
{
    va_list copy;
    va_copy(copy, ap);
    int n = vsnprintf(NULL, 0, format, copy);
    va_end(copy);
    if (n < 0)
        return NULL;
    char *s = malloc((size_t)n + 1);
    if (s)
        vsnprintf(s, (size_t)n + 1, format, ap);
    return s;
}

void sluice_diag_add(sluice_diag *diag, sluice_severity severity, const char *file, int line,
                     int column, const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    char *text = vformat(format, ap);
    va_end(ap);
    const char *label = severity == SLUICE_SEVERITY_ERROR ? "error" : "warning";
    char *message = NULL;
    const char *body = text ? text : "(out of memory formatting a message)";
    size_t n;
    if (file && line > 0) {
        n = (size_t)snprintf(NULL, 0, "%s:%d:%d: %s: %s", file, line, column > 0 ? column : 1,
                             label, body);
        message = malloc(n + 1);
        if (message)
            snprintf(message, n + 1, "%s:%d:%d: %s: %s", file, line, column > 0 ? column : 1,
                     label, body);
    } else if (file) {
        n = (size_t)snprintf(NULL, 0, "%s: %s: %s", file, label, body);
        message = malloc(n + 1);
        if (message)
            snprintf(message, n + 1, "%s: %s: %s", file, label, body);
    } else {
        n = (size_t)snprintf(NULL, 0, "%s: %s", label, body);
        message = malloc(n + 1);
        if (message)
            snprintf(message, n + 1, "%s: %s", label, body);
    }
    if (severity == SLUICE_SEVERITY_ERROR && (!text || strstr(text, "out of memory")))
        diag->resources = 1;
    free(text);
    if (severity == SLUICE_SEVERITY_ERROR)
        diag->errors++;
    if (!message)
        return;
    if (diag->count == diag->capacity) {
        size_t cap = diag->capacity ? diag->capacity * 2 : 8;
        char **m = realloc(diag->messages, cap * sizeof *m);
        if (!m) {
            free(message);
            return;
        }
        diag->messages = m;
        sluice_severity *s = realloc(diag->severities, cap * sizeof *s);
        if (!s) {
            free(message);
            return;
        }
        diag->severities = s;
        diag->capacity = cap;
    }
    diag->severities[diag->count] = severity;
    diag->messages[diag->count++] = message;
}

size_t sluice_diag_count(const sluice_diag *diag)
{
    return diag->count;
}

void sluice_diag_mark_resources(sluice_diag *diag)
{
    diag->resources = 1;
}

int sluice_diag_resources(const sluice_diag *diag)
{
    return diag->resources;
}

size_t sluice_diag_error_count(const sluice_diag *diag)
{
    return diag->errors;
}

const char *sluice_diag_message(const sluice_diag *diag, size_t index)
{
    return index < diag->count ? diag->messages[index] : NULL;
}

void sluice_diag_print(const sluice_diag *diag, FILE *stream)
{
    for (size_t i = 0; i < diag->count; i++)
        fprintf(stream, "%s\n", diag->messages[i]);
}

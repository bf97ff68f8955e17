/* Shared by the fuzz targets: the plugins stay mapped (fuzz_plugins.h). */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_plugins.h"

void fuzz_keep_plugins_mapped(const char *target)
{
    const char *directory = getenv("SLUICE_PLUGIN_PATH");
    DIR *d = directory ? opendir(directory) : NULL;
    if (!d) {
        fprintf(stderr, "%s: set SLUICE_PLUGIN_PATH to the build's plugin directory\n", target);
        exit(2);
    }
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 4 || strcmp(e->d_name + n - 3, ".so") != 0)
            continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", directory, e->d_name);
        if (!dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE))
            fprintf(stderr, "%s: %s\n", target, dlerror());
    }
    closedir(d);
}

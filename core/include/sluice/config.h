/* Build configuration shared by the core and plugins. Part of the build
 * signature checked when a plugin is loaded. */
#ifndef SLUICE_CONFIG_H
#define SLUICE_CONFIG_H

/* The floating-point type of every particle field and parameter. */
#ifndef SLUICE_REAL_TYPE
#define SLUICE_REAL_TYPE double
#endif

#endif

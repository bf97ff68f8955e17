/* Standard field declarations (part of the plugin SDK, sluice/plugin_util.h).
 *
 * The fields that many plugins share, with the units, flags and descriptions
 * every plugin of Sluice gives them. Declarations of one field by several
 * plugins must agree on type, components and units (the core refuses the
 * scene otherwise); these initialisers keep them agreeing. Each takes the
 * access of the declaring plugin (sluice_access bits: SLUICE_READ,
 * SLUICE_READ_NEIGHBOUR, SLUICE_WRITE, SLUICE_ACCUMULATE, or 0 to state only
 * that the field exists):
 *
 *     static const sluice_field_spec fields[] = {
 *         SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
 *         SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
 *         SLUICE_SPEC_DENSITY_RATE(SLUICE_ACCUMULATE),
 *     };
 *
 * The core's columns (and a checkpoint's layout) follow the order in which
 * fields are first declared: keep a plugin's order when converting it.
 *
 * | initialiser | field | units | flags | rate of (kinds) |
 * |---|---|---|---|---|
 * | SLUICE_SPEC_VELOCITY | velocity[dim] | m s^-1 | output, restart | |
 * | SLUICE_SPEC_ACCELERATION | acceleration[dim] | m s^-2 | | velocity (fluid) |
 * | SLUICE_SPEC_MASS | mass | kg | restart | |
 * | SLUICE_SPEC_DENSITY | density | kg m^-3 | output, restart | |
 * | SLUICE_SPEC_DENSITY_RATE | density_rate | kg m^-3 s^-1 | | density (fluid, wall) |
 * | SLUICE_SPEC_PRESSURE | pressure | Pa | output | |
 * | SLUICE_SPEC_SOUND_SPEED | sound_speed | m s^-1 | | |
 * | SLUICE_SPEC_EDDY_VISCOSITY | eddy_viscosity | m^2 s^-1 | output | |
 * | SLUICE_SPEC_PHASE | phase (uint8: 0 water, 1 air) | 1 | output, restart | |
 * | SLUICE_SPEC_VELOCITY_GRADIENT(dims, access) | velocity_gradient[dims^2] | s^-1 | output | |
 * | SLUICE_SPEC_KERNEL_CORRECTION(dims, access) | kernel_correction[dims^2] | 1 | | |
 *
 * The description of a field is the first non-empty one declared in the
 * scene (it is written with the field into snapshots). The _DOC forms give a
 * plugin's own wording, for example "density (imposed on open particles)". */
#ifndef SLUICE_FIELD_SPECS_H
#define SLUICE_FIELD_SPECS_H

#include "sluice/plugin.h"

#define SLUICE_SPEC_VELOCITY_DOC(access, doc)                                                     \
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", (access),                  \
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, (doc)}
#define SLUICE_SPEC_VELOCITY(access) SLUICE_SPEC_VELOCITY_DOC(access, "velocity")

/* The rate of the velocity of fluid particles: forces accumulate into it. */
#define SLUICE_SPEC_ACCELERATION(access)                                                          \
    {"acceleration", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-2", (access), 0, "velocity", \
     SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "time derivative of the velocity"}

#define SLUICE_SPEC_MASS(access)                                                                  \
    {"mass", SLUICE_TYPE_REAL, 1, "kg", (access), SLUICE_FIELD_RESTART, NULL, 0, "particle mass"}

#define SLUICE_SPEC_DENSITY_DOC(access, doc)                                                      \
    {"density", SLUICE_TYPE_REAL, 1, "kg m^-3", (access),                                      \
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, (doc)}
#define SLUICE_SPEC_DENSITY(access) SLUICE_SPEC_DENSITY_DOC(access, "mass density")

/* The rate of the density of fluid and wall particles (wall particles whose
 * density evolves, as dbc's). */
#define SLUICE_SPEC_DENSITY_RATE(access)                                                          \
    {"density_rate", SLUICE_TYPE_REAL, 1, "kg m^-3 s^-1", (access), 0, "density",              \
     SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),                 \
     "time derivative of the density"}

/* flags: SLUICE_FIELD_OUTPUT for the equation of state that computes it, 0
 * for a reader that does not ask for it to be written. */
#define SLUICE_SPEC_PRESSURE_DOC(access, flags, doc)                                              \
    {"pressure", SLUICE_TYPE_REAL, 1, "Pa", (access), (flags), NULL, 0, (doc)}
#define SLUICE_SPEC_PRESSURE(access)                                                              \
    SLUICE_SPEC_PRESSURE_DOC(access, SLUICE_FIELD_OUTPUT, "pressure from the equation of state")

#define SLUICE_SPEC_SOUND_SPEED_DOC(access, doc)                                                  \
    {"sound_speed", SLUICE_TYPE_REAL, 1, "m s^-1", (access), 0, NULL, 0, (doc)}
#define SLUICE_SPEC_SOUND_SPEED(access)                                                           \
    SLUICE_SPEC_SOUND_SPEED_DOC(access, "local speed of sound c = sqrt(dp/drho)")

#define SLUICE_SPEC_EDDY_VISCOSITY(access)                                                        \
    {"eddy_viscosity", SLUICE_TYPE_REAL, 1, "m^2 s^-1", (access), SLUICE_FIELD_OUTPUT, NULL, 0, \
     "kinematic eddy viscosity nu_T"}

/* The two_phase plugin's phase of a fluid particle (0 water, 1 air). */
#define SLUICE_SPEC_PHASE_DOC(access, flags, doc)                                                 \
    {"phase", SLUICE_TYPE_UINT8, 1, "1", (access), (flags), NULL, 0, (doc)}
#define SLUICE_SPEC_PHASE(access)                                                                 \
    SLUICE_SPEC_PHASE_DOC(access, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,                  \
                          "phase of the particle: 0 water, 1 air")

/* The fields of an equation of state: it reads the density and writes the
 * pressure and the sound speed. */
#define SLUICE_SPECS_EQUATION_OF_STATE                                                            \
    SLUICE_SPEC_DENSITY(SLUICE_READ), SLUICE_SPEC_PRESSURE(SLUICE_WRITE),                      \
        SLUICE_SPEC_SOUND_SPEED(SLUICE_WRITE)

/* Matrices of dims x dims components (row-major), declared in create() once
 * the dimension count is known (sluice_util_dimensions). */
#define SLUICE_SPEC_VELOCITY_GRADIENT(dims, access)                                               \
    {"velocity_gradient", SLUICE_TYPE_REAL, (uint32_t)((dims) * (dims)), "s^-1", (access),     \
     SLUICE_FIELD_OUTPUT, NULL, 0, "velocity gradient, component a*dims+b = d v_a / d x_b"}

#define SLUICE_SPEC_KERNEL_CORRECTION_DOC(dims, access, doc)                                      \
    {"kernel_correction", SLUICE_TYPE_REAL, (uint32_t)((dims) * (dims)), "1", (access), 0, NULL, \
     0, (doc)}
#define SLUICE_SPEC_KERNEL_CORRECTION(dims, access)                                               \
    SLUICE_SPEC_KERNEL_CORRECTION_DOC(dims, access,                                            \
                                      "kernel gradient correction matrix L, component a*dims+b " \
                                      "= L_ab")

#endif

/* sluice probe (tools/probe, docs/probe.md): fields interpolated from a
 * run's snapshots. An analytic field written into a snapshot is recovered
 * with the second-order error of the Shepard-normalised kernel sum on a
 * lattice (observed order about 2 at three spacings); at the point gauge's
 * points and times the probe gives the gauge's values to round-off (the same
 * kernel and sum); lines and planes place their points as documented; bad
 * input is refused with one message, exit 2, and no output file. */
#include <check.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"

/* A square of still fluid without walls or gravity: its snapshot at t = 0
 * holds the lattice, each particle of volume dx^2. */
static const char lattice_scene[] = "dimensions: 2\n"
                                    "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
                                    "time: {end: %g}\n"
                                    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                                    "geometry:\n"
                                    "  fluid: [{shape: box, min: [0, 0], max: [1, 1]}]\n"
                                    "plugins:\n"
                                    "  cubic_spline: {}\n"
                                    "  tait: {speed_of_sound: 10}\n"
                                    "  continuity: {}\n"
                                    "  pressure_gradient: {}\n"
                                    "  time_step: {}\n"
                                    "  symplectic: {}\n"
                                    "  hdf5: {interval: 1}\n";

static double analytic(double x, double y)
{
    return sin(M_PI * x) * cos(0.5 * M_PI * y) + 0.3 * x * y;
}

/* Runs `scene_format` (formatted with spacing and end) into a new run
 * directory, returned. */
static char *run_scene(const char *tag, const char *scene_text)
{
    char *dir = test_scratch(tag);
    ck_assert_ptr_nonnull(dir);
    char *scene = test_write_file(dir, "scene.yaml", scene_text);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/run --quiet --threads 1", scene, dir), 0);
    const int status = test_sluice(args, &output);
    ck_assert_msg(status == 0, "sluice run failed (%d): %s", status, output);
    char *run = NULL;
    ck_assert_int_ge(asprintf(&run, "%s/run", dir), 0);
    free(args);
    free(output);
    free(scene);
    free(dir);
    return run;
}

/* Overwrites dataset `velocity` of the snapshot with (f(x, y), 0). */
static void write_analytic_velocity(const char *snapshot)
{
    hid_t file = H5Fopen(snapshot, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    hid_t position = H5Dopen2(file, "position", H5P_DEFAULT);
    hid_t space = H5Dget_space(position);
    hsize_t dims[2];
    ck_assert_int_eq(H5Sget_simple_extent_dims(space, dims, NULL), 2);
    double *x = malloc(dims[0] * 2 * sizeof *x), *v = calloc(dims[0] * 2, sizeof *v);
    ck_assert(x && v);
    ck_assert_int_ge(H5Dread(position, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, x), 0);
    for (hsize_t i = 0; i < dims[0]; i++)
        v[2 * i] = analytic(x[2 * i], x[2 * i + 1]);
    hid_t velocity = H5Dopen2(file, "velocity", H5P_DEFAULT);
    ck_assert_int_ge(H5Dwrite(velocity, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v), 0);
    H5Dclose(velocity);
    H5Sclose(space);
    H5Dclose(position);
    H5Fclose(file);
    free(x);
    free(v);
}

/* The rows of a probe's CSV output (header skipped): up to `max` rows of
 * `columns` numbers each; returns the row count. */
static int csv_rows(const char *text, double *values, int columns, int max)
{
    const char *line = strchr(text, '\n');
    int rows = 0;
    while (line && line[1] && rows < max) {
        const char *p = line + 1;
        for (int c = 0; c < columns; c++) {
            char *end;
            values[rows * columns + c] = strtod(p, &end);
            ck_assert_msg(end != p, "not a number in row %d: %.60s", rows, p);
            p = *end == ',' ? end + 1 : end;
        }
        rows++;
        line = strchr(line + 1, '\n');
    }
    return rows;
}

/* Runs `sluice probe ARGS` (stdout only, unless `merge`); its status. */
static int probe(const char *args, char **output, int merge)
{
    char *command = NULL;
    ck_assert_int_ge(asprintf(&command, "%s/sluice probe %s%s", test_build_dir(), args,
                              merge ? " 2>&1" : " 2>/dev/null"),
                     0);
    const int status = test_popen(command, output);
    free(command);
    return status;
}

/* The largest error of the probed f at 3 x 3 interior points. */
static double lattice_error(double dx, double *support_error)
{
    char scene[2048];
    snprintf(scene, sizeof scene, lattice_scene, dx, 1e-6);
    char *run = run_scene("probe-lattice", scene);
    char *snapshot = NULL;
    ck_assert_int_ge(asprintf(&snapshot, "%s/particles_000000.h5", run), 0);
    write_analytic_velocity(snapshot);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args,
                              "%s --fields velocity --times 0 --points "
                              "'0.3,0.3;0.5,0.3;0.7,0.3;0.3,0.5;0.5,0.5;0.7,0.5;0.3,0.7;0.5,0.7;0.71,"
                              "0.69'",
                              run),
                     0);
    ck_assert_int_eq(probe(args, &output, 0), 0);
    ck_assert_msg(strncmp(output, "time,point,x,y,velocity_x,velocity_y,support\n", 45) == 0,
                  "header: %.80s", output);
    double rows[9 * 7];
    ck_assert_int_eq(csv_rows(output, rows, 7, 9), 9);
    double worst = 0;
    *support_error = 0;
    for (int k = 0; k < 9; k++) {
        const double *r = rows + 7 * k;
        ck_assert_double_eq(r[0], 0);
        ck_assert_double_eq(r[1], k);
        worst = fmax(worst, fabs(r[4] - analytic(r[2], r[3])));
        ck_assert_double_eq_tol(r[5], 0, 1e-14);
        *support_error = fmax(*support_error, fabs(r[6] - 1));
    }
    free(args);
    free(output);
    free(snapshot);
    free(run);
    return worst;
}

/* Shepard's estimate of a smooth f on a lattice errs by (1/2) f'' times the
 * kernel's second moment, ~h^2: order 2 as dx halves with h / dx fixed. */
START_TEST(analytic_field_converges)
{
    const double spacing[3] = {0.04, 0.02, 0.01};
    double error[3], support[3];
    for (int k = 0; k < 3; k++) {
        error[k] = lattice_error(spacing[k], &support[k]);
        fprintf(stderr, "probe: dx = %g m: max error %.3e, |sum V W - 1| %.3e\n", spacing[k],
                error[k], support[k]);
    }
    for (int k = 0; k < 2; k++) {
        const double order = log(error[k] / error[k + 1]) / log(2);
        fprintf(stderr, "probe: observed order %.2f\n", order);
        ck_assert_msg(order > 1.7 && order < 2.3, "order %.2f between dx = %g and %g", order,
                      spacing[k], spacing[k + 1]);
    }
    /* the leading term bounds the finest error: |f''| <= pi^2 (1.1) and the
     * cubic spline's second moment over h^2 is under 1 */
    const double h = 1.3 * spacing[2];
    ck_assert_msg(error[2] < 0.5 * 1.1 * M_PI * M_PI * h * h, "error %.3e", error[2]);
    /* the kernel sum of a lattice is 1 to about 1 % for h = 1.3 dx */
    ck_assert_msg(support[2] < 0.02, "support off by %.3e", support[2]);
}
END_TEST

/* A still tank with point gauges and snapshots at the same times. */
static const char gauge_scene[] =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.06}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1.0, 1.0]}]\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 22.1}\n"
    "  continuity: {}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  point_gauge: {points: [[0.31, 0.05], [0.5, 0.25], [0.77, 0.43], [0.5, 0.9]], interval: "
    "0.02, fields: velocity}\n"
    "  hdf5: {interval: 0.02}\n";

/* The same kernel sum as point_gauge: its rows to round-off. */
START_TEST(matches_point_gauge)
{
    char *run = run_scene("probe-gauge", gauge_scene);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args,
                              "%s --fields velocity --points "
                              "'0.31,0.05;0.5,0.25;0.77,0.43;0.5,0.9'",
                              run),
                     0);
    ck_assert_int_eq(probe(args, &output, 0), 0);
    double rows[16 * 7];
    const int n = csv_rows(output, rows, 7, 16);
    ck_assert_int_eq(n, 16); /* t = 0, 0.02, 0.04, 0.06 */
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/points.csv", run), 0);
    char *gauge = test_read_file(path);
    ck_assert_ptr_nonnull(gauge);
    double g[4 * 9];
    ck_assert_int_eq(csv_rows(gauge, g, 9, 4), 4);
    double largest = 0;
    for (int k = 0; k < 16; k++) {
        const double *r = rows + 7 * k, *row = g + 9 * (k / 4);
        const int point = (int)r[1];
        ck_assert_double_eq_tol(r[0], row[0], 1e-12);
        for (int c = 0; c < 2; c++) {
            const double want = row[1 + 2 * point + c];
            if (point == 3) { /* above the water: outside the fluid */
                ck_assert_msg(isnan(r[4 + c]) && isnan(want), "point 3 not nan");
                continue;
            }
            largest = fmax(largest, fabs(want));
            /* both printed to 10 significant digits (the tables' %.10g) */
            ck_assert_msg(fabs(r[4 + c] - want) <= 1.5e-9 * fabs(want) + 1e-15,
                          "t = %g point %d: probe %.12g, gauge %.12g", r[0], point, r[4 + c],
                          want);
        }
    }
    ck_assert_msg(largest > 1e-6, "the tank never moved (%g m/s): the test shows nothing",
                  largest);
    free(gauge);
    free(path);
    free(args);
    free(output);
    free(run);
}
END_TEST

/* --line: N points from end to end; --plane: u fastest; --out atomic. */
START_TEST(line_and_plane)
{
    char scene[2048];
    snprintf(scene, sizeof scene, lattice_scene, 0.05, 1e-6);
    char *run = run_scene("probe-shapes", scene);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(
        asprintf(&args, "%s --fields density --times last --line '0.1,0.2;0.9,0.6' --count 5", run),
        0);
    ck_assert_int_eq(probe(args, &output, 0), 0);
    double rows[5 * 6];
    ck_assert_int_eq(csv_rows(output, rows, 6, 5), 5);
    for (int k = 0; k < 5; k++) {
        ck_assert_double_eq_tol(rows[6 * k + 2], 0.1 + 0.2 * k, 1e-12);
        ck_assert_double_eq_tol(rows[6 * k + 3], 0.2 + 0.1 * k, 1e-12);
        /* still water at rest density: Shepard is exact for a constant */
        ck_assert_double_eq_tol(rows[6 * k + 4], 1000, 1e-9);
    }
    free(args);
    free(output);
    ck_assert_int_ge(asprintf(&args,
                              "%s --fields density --plane '0.2,0.2;0.8,0.2;0.2,0.5' --count 4,3 "
                              "--out %s/plane.csv",
                              run, run),
                     0);
    ck_assert_int_eq(probe(args, &output, 0), 0);
    free(output);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/plane.csv", run), 0);
    char *text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    double plane[12 * 6];
    ck_assert_int_eq(csv_rows(text, plane, 6, 12), 12);
    for (int k = 0; k < 12; k++) {
        ck_assert_double_eq_tol(plane[6 * k + 2], 0.2 + 0.2 * (k % 4), 1e-12);
        ck_assert_double_eq_tol(plane[6 * k + 3], 0.2 + 0.15 * (k / 4), 1e-12);
    }
    char *listing = NULL;
    char *command = NULL;
    ck_assert_int_ge(asprintf(&command, "ls %s | grep -c tmp", run), 0);
    test_popen(command, &listing);
    ck_assert_int_eq(atoi(listing), 0); /* no temporary file left */
    free(listing);
    free(command);
    free(text);
    free(path);
    free(args);
    free(run);
}
END_TEST

/* Each bad input: exit 2, one message naming the problem, no output file. */
START_TEST(bad_input)
{
    char scene[2048];
    snprintf(scene, sizeof scene, lattice_scene, 0.05, 1e-6);
    char *run = run_scene("probe-bad", scene);
    static const struct {
        const char *args, *message;
    } cases[] = {
        {"--points '0.5,0.5'", "give a run directory and --fields"},
        {"--fields velocity", "give one of --points, --line and --plane"},
        {"--fields velocty --points '0.5,0.5'", "no real field 'velocty'"},
        {"--fields velocity --points '0.5'", "point 1 '0.5' is not 2 numbers"},
        {"--fields velocity --points '0.5,0.5' --times 0.3", "no snapshot at t = 0.3 s"},
        {"--fields velocity --line '0,0;1,1'", "--line needs --count"},
        {"--fields velocity --line '0,0;1,1' --count 1", "--line takes 2 points"},
        {"--fields velocity --points '0.5,0.5' --correction linear", "unknown option"},
        {"--fields velocity --points '0.5,0.5' --prefix nothing", "no snapshots nothing_NNNNNN"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char *args = NULL, *output = NULL;
        ck_assert_int_ge(asprintf(&args, "%s %s --out %s/bad.csv", run, cases[k].args, run), 0);
        ck_assert_int_eq(probe(args, &output, 1), 2);
        ck_assert_msg(strstr(output, cases[k].message), "case %zu: %s", k, output);
        ck_assert_int_eq(test_count_lines(output, "error"), 1);
        free(args);
        free(output);
    }
    /* a corrupt snapshot and a missing run directory */
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/particles_000009.h5", run), 0);
    free(test_write_file(run, "particles_000009.h5", "not HDF5 at all\n"));
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "%s --fields velocity --points '0.5,0.5' --out %s/bad.csv",
                              run, run),
                     0);
    ck_assert_int_eq(probe(args, &output, 1), 2);
    ck_assert_msg(strstr(output, "particles_000009.h5") && strstr(output, "not HDF5"), "%s",
                  output);
    free(args);
    free(output);
    unlink(path);
    ck_assert_int_ge(asprintf(&args, "%s/nowhere --fields velocity --points '0.5,0.5'", run), 0);
    ck_assert_int_eq(probe(args, &output, 1), 2);
    ck_assert_msg(strstr(output, "nowhere/scene.resolved.yaml"), "%s", output);
    free(args);
    free(output);
    /* a snapshot without mass (as written before hdf5 writer 1.2.0) */
    ck_assert_int_ge(asprintf(&args, "%s/particles_000000.h5", run), 0);
    hid_t file = H5Fopen(args, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    ck_assert_int_ge(H5Ldelete(file, "mass", H5P_DEFAULT), 0);
    H5Fclose(file);
    free(args);
    ck_assert_int_ge(asprintf(&args, "%s --fields velocity --points '0.5,0.5' --times 0", run), 0);
    ck_assert_int_eq(probe(args, &output, 1), 2);
    ck_assert_msg(strstr(output, "no dataset 'mass'"), "%s", output);
    free(args);
    free(output);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/bad.csv", run), 0);
    ck_assert(!test_exists(path));
    free(path);
    free(run);
}
END_TEST

/* A string attribute of the snapshot's root (malloc'd). */
static char *string_attribute(hid_t file, const char *name)
{
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    ck_assert_msg(a >= 0, "no attribute '%s'", name);
    hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    char *value = NULL;
    ck_assert_int_ge(H5Aread(a, type, &value), 0);
    char *copy = strdup(value);
    H5free_memory(value);
    H5Tclose(type);
    H5Aclose(a);
    return copy;
}

/* run.json and every snapshot say what produced them, and a snapshot holds
 * what a reader needs to interpolate: mass (rho0 dx^2 in 2D), density,
 * the kernel and its support. */
START_TEST(provenance_and_interpolation_data)
{
    char scene[2048];
    snprintf(scene, sizeof scene, lattice_scene, 0.05, 1e-6);
    char *dir = test_scratch("probe-provenance");
    char *path = test_write_file(dir, "scene.yaml", scene);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args,
                              "run %s --out %s/run --quiet --set 'title=a b' --set "
                              "checkpoint.interval=5e-7",
                              path, dir),
                     0);
    ck_assert_int_eq(test_sluice(args, &output), 0);
    free(output);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/run/run.json", dir), 0);
    char *json = test_read_file(path);
    ck_assert_ptr_nonnull(json);
    char host[256] = "";
    gethostname(host, sizeof host);
    char want[512];
    snprintf(want, sizeof want, "\"host\": \"%s\"", host);
    ck_assert_msg(strstr(json, want), "%s", json);
    ck_assert_msg(strstr(json, "\"kernel\": \"cubic_spline\""), "%s", json);
    ck_assert_msg(strstr(json, "--set 'title=a b'"), "command line not quoted: %s", json);
    const char *date = strstr(json, "\"date\": \"");
    ck_assert_ptr_nonnull(date);
    int y, mo, d, h, mi, s;
    ck_assert_int_eq(sscanf(date + 9, "%4d-%2d-%2dT%2d:%2d:%2dZ", &y, &mo, &d, &h, &mi, &s), 6);
    ck_assert(y >= 2026 && mo >= 1 && mo <= 12 && d >= 1 && d <= 31);
    const char *revision = strstr(json, "\"git_revision\": \"");
    ck_assert_ptr_nonnull(revision);
    ck_assert_msg(revision[17] != '"', "empty git revision");
    ck_assert_msg(strstr(json, "\"build\": \"") && strstr(json, "buildtype"), "%s", json);

    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/run/particles_000000.h5", dir), 0);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    static const char *const same[] = {"git_revision", "build", "command_line", "date", "host",
                                       "kernel"};
    for (size_t k = 0; k < sizeof same / sizeof *same; k++) {
        char *value = string_attribute(file, same[k]), *quoted = NULL;
        ck_assert_int_ge(asprintf(&quoted, "\"%s\": \"%s\"", same[k], value), 0);
        if (strcmp(same[k], "command_line") != 0) /* (quotes are escaped in JSON) */
            ck_assert_msg(strstr(json, quoted), "snapshot %s differs from run.json", quoted);
        free(quoted);
        free(value);
    }
    double support = 0;
    hid_t a = H5Aopen(file, "kernel_support", H5P_DEFAULT);
    ck_assert_int_ge(H5Aread(a, H5T_NATIVE_DOUBLE, &support), 0);
    H5Aclose(a);
    ck_assert_double_eq(support, 2); /* the cubic spline reaches 2h */
    hid_t mass = H5Dopen2(file, "mass", H5P_DEFAULT), density = H5Dopen2(file, "density", H5P_DEFAULT);
    ck_assert(mass >= 0 && density >= 0);
    double m[4], rho[4];
    hid_t space = H5Dget_space(mass);
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, NULL);
    ck_assert_int_eq(n, 400); /* 20 x 20 */
    double *all = malloc(n * sizeof *all), *all_rho = malloc(n * sizeof *all_rho);
    ck_assert_int_ge(H5Dread(mass, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, all), 0);
    ck_assert_int_ge(H5Dread(density, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, all_rho), 0);
    for (int k = 0; k < 4; k++) {
        m[k] = all[k * 97 % n];
        rho[k] = all_rho[k * 97 % n];
        ck_assert_double_eq_tol(m[k], 1000 * 0.05 * 0.05, 1e-12);
        ck_assert_double_eq_tol(rho[k], 1000, 1e-9);
    }
    free(all);
    free(all_rho);
    H5Sclose(space);
    H5Dclose(mass);
    H5Dclose(density);
    H5Fclose(file);
    /* a checkpoint and the writer's vertex index record the same provenance */
    char *command = NULL, *files = NULL;
    ck_assert_int_ge(asprintf(&command, "ls %s/run/checkpoint_*.h5 | head -1 | tr -d '\\n'; echo "
                                        "' %s/run/particles_vertices.h5'",
                              dir, dir),
                     0);
    ck_assert_int_eq(test_popen(command, &files), 0);
    char *save = NULL;
    for (char *name = strtok_r(files, " \n", &save); name; name = strtok_r(NULL, " \n", &save)) {
        file = H5Fopen(name, H5F_ACC_RDONLY, H5P_DEFAULT);
        ck_assert_msg(file >= 0, "cannot open '%s'", name);
        for (size_t k = 0; k < 5; k++) {
            char *value = string_attribute(file, same[k]), *quoted = NULL;
            ck_assert_int_ge(asprintf(&quoted, "\"%s\": \"%s\"", same[k], value), 0);
            if (k != 2)
                ck_assert_msg(strstr(json, quoted), "%s: %s differs from run.json", name, quoted);
            free(quoted);
            free(value);
        }
        H5Fclose(file);
    }
    free(command);
    free(files);
    free(json);
    free(path);
    free(args);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("probe");
    TCase *tc = tcase_create("probe");
    tcase_set_timeout(tc, 240);
    tcase_add_test(tc, analytic_field_converges);
    tcase_add_test(tc, matches_point_gauge);
    tcase_add_test(tc, line_and_plane);
    tcase_add_test(tc, bad_input);
    tcase_add_test(tc, provenance_and_interpolation_data);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}

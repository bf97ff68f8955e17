# Dissolved oxygen at the monitoring points of Cheng's stepped spillway
# (configs/stepped_spillway_cheng.yaml) against seed 001's table 4 and the
# reaeration rate against its table 5:
#   awk -F, -f tools/cheng-do.awk -v from=2 -v to=3 RUN/points.csv
# The gauge file has 6 stations (points 2-7) of `per` points each (default
# 15) with the columns pK_velocity_x, pK_velocity_y, pK_air_fraction,
# pK_dissolved_oxygen in that order (fields: velocity, air_fraction,
# dissolved_oxygen). At each sample in [from, to] s a station's value is the
# mean DO over its points wet with water (not nan); the station's figure is
# the mean of those over the samples that have one (a "mixed" reading: the
# seed does not say where across the flow Cheng sampled). The discharge-
# weighted mean (weights: the water's speed) is printed beside it.
# Options: -v per=N, -v cs=10.48, -v cu=1.29.
BEGIN {
    if (per == "") per = 15
    if (cs == "") cs = 10.48
    if (cu == "") cu = 1.29
    if (from == "") from = 0
    if (to == "") to = 1e30
    split("2.94,3.40,4.01,4.32,4.91,5.31", experiment, ",")
    split("2.12,3.21,3.74,4.62,4.92,5.02", seed, ",")
}
NR == 1 {
    for (i = 1; i <= NF; i++) {
        if ($i ~ /_dissolved_oxygen$/) { n++; col_do[n] = i }
        if ($i ~ /_velocity_x$/) { m++; col_u[m] = i }
    }
    if (n != 6 * per) {
        printf "cheng-do.awk: %s has %d dissolved_oxygen columns, expected 6 stations x %d\n", FILENAME, n, per > "/dev/stderr"
        bad = 1; exit 2
    }
    next
}
$1 + 0 >= from && $1 + 0 <= to {
    for (s = 1; s <= 6; s++) {
        sum = 0; wet = 0; wsum = 0; w = 0
        for (k = 1; k <= per; k++) {
            p = (s - 1) * per + k
            c = $(col_do[p]); u = $(col_u[p]); v = $(col_u[p] + 1)
            if (c == "nan" || c == "" ) continue
            sum += c; wet++
            speed = sqrt(u * u + v * v); wsum += speed * c; w += speed
        }
        if (wet > 0) { mean[s] += sum / wet; samples[s]++ }
        if (w > 0) { wmean[s] += wsum / w; wsamples[s]++ }
    }
}
END {
    if (bad) exit 2
    printf "# DO at Cheng's points, mean over the water, samples in [%g, %g] s\n", from, to
    print "point,sluice_mg_L,sluice_flux_weighted_mg_L,samples,experiment_mg_L,error_pct,seed001_mg_L,seed001_error_pct"
    for (s = 1; s <= 6; s++) {
        v = samples[s] ? mean[s] / samples[s] : "nan"
        fw = wsamples[s] ? wmean[s] / wsamples[s] : "nan"
        e = samples[s] ? 100 * (experiment[s] - v) / experiment[s] : "nan"
        printf "%d,%.3f,%.3f,%d,%.2f,%.1f,%.2f,%.1f\n", s + 1, v, fw, samples[s], experiment[s], e, seed[s], 100 * (experiment[s] - seed[s]) / experiment[s]
        if (samples[s]) { abs_sum += (e < 0 ? -e : e); worst = ((e < 0 ? -e : e) > worst ? (e < 0 ? -e : e) : worst); counted++ }
    }
    if (samples[6]) {
        cd = mean[6] / samples[6]
        r = (cs - cu) / (cs - cd)
        printf "# reaeration rate r = (Cs - Cu)/(Cs - Cd) = %.3f (experiment 1.78, seed 001 1.68); error %.1f %%\n", r, 100 * (1.78 - r) / 1.78
    }
    if (counted) printf "# mean |error| %.1f %%, worst %.1f %% over %d points (seed 001: mean 8.8 %%, worst 27.9 %%)\n", abs_sum / counted, worst, counted
}

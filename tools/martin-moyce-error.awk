# Worst relative error of a dam-break front against Martin & Moyce (1952):
#   awk -F, -f tools/martin-moyce-error.awk tests/scenes/data/martin_moyce_1952_n2.csv RUN/front.csv
# The first file is the experiment (rows a,T,Z; the a = 2.25 in column is
# used, with Z = 1 at T = 0 added), the second a front table (time,x_front,
# header first). Prints the signed error (Z_run - Z_exp) / Z_exp of largest
# magnitude over T = t sqrt(2 g / L) = 0.5, 0.55, ..., 2.5 (L = 1 m) up to the
# run's last sample, both series interpolated linearly; "nan" without samples.
# Used by tools/boundary-study.sh and tools/benchmark.sh.
function lerp(xs, ys, m, x,   i) {
    for (i = 2; i <= m; i++)
        if (x <= xs[i]) return ys[i-1] + (ys[i] - ys[i-1]) * (x - xs[i-1]) / (xs[i] - xs[i-1])
    return ys[m]
}
FNR == 1 { file++ }
file == 1 && $0 !~ /^#/ && $1 == 2.25 { m++; et[m] = $2; ez[m] = $3 }
file == 2 && FNR > 1 && $1 == $1 + 0 { k++; st[k] = $1; sx[k] = $2 }
END {
    for (i = m; i >= 1; i--) { et[i+1] = et[i]; ez[i+1] = ez[i] } et[1] = 0; ez[1] = 1; m++
    s = sqrt(2 * 9.81); worst = 0; n = 0
    for (T = 0.5; T <= 2.5 + 1e-9; T += 0.05) {
        if (T / s > st[k]) break
        e = (lerp(st, sx, k, T / s) - lerp(et, ez, m, T)) / lerp(et, ez, m, T)
        if ((e < 0 ? -e : e) > (worst < 0 ? -worst : worst)) worst = e
        n++
    }
    if (n) printf "%.4f", worst; else printf "nan"
}

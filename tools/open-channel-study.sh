#!/bin/sh
# Turbulent open-channel flow (docs/validation.md): 2D, periodic in x, depth
# H = 0.1 m over a flat DBC bed, slope S = 0.0025 (gravity tilted by the
# slope), free surface, c0 = 10 m/s (> 10 u_max and > 10 sqrt(g H)), h = 1.5 dx,
# 12 dx long. It runs the `study` case of the turbulence test program
# (tests/plugins/turbulence/test_turbulence.c, run_open_channel), which for every case measures,
# time-averaged over the last T_AVERAGE seconds:
#   - u* = sqrt(g S H) from the exact momentum balance (fluid mass);
#   - the bulk velocity U and the bed friction / driving force ratio
#     (1 - (dU/dt) / (g S): 1 in a steady state);
#   - the stress balance nu_T du/dy = u*^2 (1 - y/H) in the bins at least a
#     kernel radius from bed and surface (mean and max error, in u*^2);
#   - the slope of u against the mixing-length profile shape Phi(y/H) (the log
#     law with the linear stress distribution), in units of u*/kappa, and
#     against ln y for y <= 0.3 H;
#   - B_dx in u/u* = (1/kappa) ln(y/dx) + B_dx near the bed (no viscous
#     sublayer: the SPH wall acts as a roughness), the equivalent Nikuradse
#     sand roughness ks/dx = exp(kappa (8.5 - B_dx)) of the rough-wall law
#     u/u* = (1/kappa) ln(y/ks) + 8.5, and the depth-averaged velocity that
#     the profile (1/kappa) Phi + const with this B_dx implies,
#     U/u* = B_dx + (-2/3 - ln(dx/H) - 2 + 2 ln 2)/kappa (int_0^1 Phi = -2/3),
#     against the measured bulk velocity.
# Cases are MODEL:FORM:H_OVER_DX:T_END:T_AVERAGE:START, START = rest or the
# B_dx of the log profile the run starts from.
#
#   tools/open-channel-study.sh [BUILD_DIR] [CASE ...]
#
# Writes runs/open-channel-study/summary.csv and profiles.csv and prints the
# summary. The default cases take about 25 minutes on one core.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
[ $# -gt 0 ] && shift
cases=${*:-"mixing_length:eddy_viscosity:10:120:20:rest
mixing_length:eddy_viscosity:10:60:20:10
mixing_length:eddy_viscosity:20:60:20:10
mixing_length:tensor:10:120:20:rest
mixing_length:tensor:20:60:20:10
k_epsilon:eddy_viscosity:10:60:20:10
k_epsilon:eddy_viscosity:20:60:20:10"}
out=${OUT:-runs/open-channel-study}
mkdir -p "$out"
SLUICE_OPEN_CHANNEL_STUDY=$(echo $cases) \
    SLUICE_PLUGIN_PATH="$PWD/$build/plugins" SLUICE_BUILD_DIR="$PWD/$build" \
    SLUICE_SOURCE_DIR="$PWD" CK_RUN_CASE=study CK_DEFAULT_TIMEOUT=36000 \
    OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" \
    "$build/tests/test_turbulence" >"$out/raw.txt" 2>"$out/log.txt" || {
    cat "$out/raw.txt" "$out/log.txt" >&2
    exit 1
}
{
    echo "model,form,h_over_dx,start,particles,steps,wall_s,t_end_s,u_star,bulk_U,bulk_U_over_u_star,friction_over_driving,mach,slope_phi_over_u_star_kappa,slope_ln_y_over_u_star_kappa,stress_error_mean,stress_error_max,B_dx,ks_over_dx,U_over_u_star_from_profile"
    awk -F, '$1 == "study" {
        sub(/^study,/, "")
        kappa = 0.41; B = $18; n = $3
        printf "%s,%.3f,%.3f\n", $0, exp(kappa * (8.5 - B)), B + (-2 / 3 + log(n) - 2 + 2 * log(2)) / kappa
    }' "$out/raw.txt"
} >"$out/summary.csv"
{
    echo "model,form,h_over_dx,start,y_over_H,u_over_u_star,log_law,stress_over_u_star2,nu_T_over_u_star_H,S_over_du_dy,k_sqrt_c_mu_over_u_star2"
    awk -F, '$1 == "profile" { sub(/^profile,/, ""); print }' "$out/raw.txt"
} >"$out/profiles.csv"
cat "$out/summary.csv"

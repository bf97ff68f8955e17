#!/bin/sh
# Seed 004 T1: the long run's drop type, per-10-s wave share and spectra
# (docs/validation.md, "T1 to 180 s"). After tools/abrupt-drop-study.sh with T1.
#   TO=<end of the window, s> [R=runs/abrupt-drop-study/T1] sh tools/abrupt-drop-t1-analysis.sh
set -eu
cd "$(dirname "$0")/.."
R=${R:-runs/abrupt-drop-study/T1}
TO=${TO:-200}
cat $R/drop_type.txt 2>/dev/null | grep -E "window|fraction|rate|type"
echo "-- per 10 s: wave fraction, B fraction, mean eta at x=0.7 (m)"
awk -F, 'NR>1 {b=int($1/10)*10; n[b]++; if ($3==2) w[b]++; if ($3==1) B[b]++} END {for (k in n) printf "%d %.2f %.2f\n", k, w[k]/n[k], B[k]/n[k]}' $R/analysis/drop_type.csv | LC_ALL=C sort -k1,1 > $R/analysis/wave_share_10s.txt
awk -F, 'NR>1 && $1>=10 {b=int($1/10)*10; s[b]+=$14; n[b]++} END {for (k in s) printf "%d %.4f\n", k, s[k]/n[k]}' $R/free_surface.csv | LC_ALL=C sort -k1,1 > $R/analysis/eta_x0.7_mean_10s.txt
LC_ALL=C join $R/analysis/wave_share_10s.txt $R/analysis/eta_x0.7_mean_10s.txt
echo "-- wave indicator series"
awk -F, 'NR==1 {print "time,wave"; next} $3>=0 {print $1 "," ($3==2 ? 1 : 0)}' $R/analysis/drop_type.csv > $R/analysis/wave_indicator.csv
for c in eta_x12 eta_x22 bed_pressure.csv:p0_pressure analysis/wave_indicator.csv:wave; do
  o=$R/analysis/spectrum_$(echo $c | tr ':/.' '___')
  build/tools/sluice-analyze spectrum $R --column $c --from 10 --to $TO --fmin 0.005 --fmax 2 --out $o | grep -E "^df|f_peak|amplitude_peak" | tr '\n' ' '
  echo " [$c]"
  f=$(ls $o/*.csv)
  echo "   top in 0.005-0.5 Hz: $(awk -F, 'NR>1 && $1>=0.005 && $1<=0.5' $f | sort -t, -k2 -gr | head -5 | awk -F, '{printf "%.4f Hz (%.3g)  ", $1, $2}')"
  echo "   largest in 0.05-0.2 Hz: $(awk -F, 'NR>1 && $1>=0.05 && $1<=0.2' $f | sort -t, -k2 -gr | head -3 | awk -F, '{printf "%.4f Hz (%.3g)  ", $1, $2}')"
  echo "   mean per 0.02 Hz band to 0.2 Hz: $(awk -F, 'NR>1 && $1<0.2 {b=int($1/0.02); s[b]+=$2; n[b]++} END {for (k=0;k<10;k++) if (n[k]) printf "%.2f-%.2f %.3g; ", k*0.02, (k+1)*0.02, s[k]/n[k]}' $f)"
done

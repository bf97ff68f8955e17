// Writes DIR/CASE.bi4, the particle file that DualSPHysics' GenCase writes,
// with DualSPHysics' own writer (JPartDataBi4), from a raw particle list.
// Used by tools/peers/dualsphysics-dam-break-3d when GenCase_linux64 is not
// at hand; built by that script against DualSPHysics' src/source.
//
//   dualsphysics-case-bi4 RAW DIR CASE
//
// RAW: uint64 np, nfixed, nfluid; double dp, h, b, rho0, gamma, massbound,
// massfluid; then np x (double x, y, z), np x uint32 id, np x float rho.
// Particles are ordered as DualSPHysics expects: fixed boundary first.
#include "JPartDataBi4.h"
#include "Functions.h"
#include <cfloat>
#include <cstdio>
#include <vector>

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s RAW DIR CASE\n", argv[0]);
    return 2;
  }
  FILE *f = fopen(argv[1], "rb");
  if (!f) { perror(argv[1]); return 1; }
  unsigned long long n[3];
  double c[7];
  if (fread(n, sizeof n, 1, f) != 1 || fread(c, sizeof c, 1, f) != 1) return 1;
  const unsigned np = unsigned(n[0]);
  std::vector<tdouble3> pos(np);
  std::vector<unsigned> idp(np);
  std::vector<float> rho(np);
  std::vector<tfloat3> vel(np, TFloat3(0));
  if (fread(pos.data(), sizeof(tdouble3), np, f) != np
      || fread(idp.data(), sizeof(unsigned), np, f) != np
      || fread(rho.data(), sizeof(float), np, f) != np) {
    fprintf(stderr, "%s: short file\n", argv[1]);
    return 1;
  }
  fclose(f);
  tdouble3 lo = pos[0], hi = pos[0];
  for (const tdouble3 &p : pos) {
    lo = MinValues(lo, p);
    hi = MaxValues(hi, p);
  }
  try {
    JPartDataBi4 pd;
    pd.ConfigBasic(0, 1, "", "dualsphysics-case-bi4", argv[3], false, 0, argv[2]);
    pd.ConfigParticles(np, n[1], 0, 0, n[2], lo, hi);
    pd.ConfigCtes(c[0], c[1], c[2], c[3], c[4], c[5], c[6]);
    pd.AddPartInfo(0, 0, np, 0, 0, 0, lo, hi);
    pd.AddPartData(np, idp.data(), pos.data(), vel.data(), rho.data());
    pd.SaveFileCase(argv[3]);
  } catch (const std::exception &e) {
    fprintf(stderr, "dualsphysics-case-bi4: %s\n", e.what());
    return 1;
  }
  return 0;
}

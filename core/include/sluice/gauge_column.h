/* Shared by the gauges that sample vertical columns of points
 * (free_surface_gauge, section_gauge): per-gauge list parameters and the
 * free-surface crossing of the kernel sum. Header only (plugins never link
 * against each other). */
#ifndef SLUICE_GAUGE_COLUMN_H
#define SLUICE_GAUGE_COLUMN_H

#include <math.h>

#include "sluice/plugin_util.h"

/* Value k of a list parameter given as one value for all gauges or one per
 * gauge; `absent` when the list is empty. */
static inline sluice_real sluice_gauge_list_value(const sluice_real_list *list,
                                                  sluice_index k,
                                                  sluice_real absent) {
  if (list->count == 0)
    return absent;
  return list->values[list->count == 1 ? 0 : k];
}

/* Refuses a list that is neither one value nor one per gauge; `gauges`
 * names them in the message ("positions", "sections"). */
static inline int sluice_gauge_check_list(const sluice_api *api,
                                          sluice_host *host, const char *name,
                                          const sluice_real_list *list,
                                          sluice_index count,
                                          const char *gauges) {
  if (list->count > 1 && list->count != count) {
    api->messages->error(host,
               "'%s' lists %u values for %u %s: give one value for all or one "
               "per %.*s",
               name, list->count, count, gauges, (int)strlen(gauges) - 1,
               gauges);
    return SLUICE_ERROR;
  }
  return SLUICE_OK;
}

/* The highest elevation where the kernel sum S of a column of n samples
 * (S[i * stride], elevations points[3 i + axis], increasing) crosses
 * `threshold` from above, by linear interpolation between samples; the top
 * sample's elevation when it is wet; nan when no sample is. */
static inline double sluice_gauge_surface(sluice_index n, const double *S,
                                          size_t stride,
                                          const sluice_real *points,
                                          uint32_t axis, double threshold) {
#define SG_S(i) S[(size_t)(i)*stride]
#define SG_Y(i) ((double)points[3 * (size_t)(i) + axis])
  if (n == 0)
    return NAN;
  if (SG_S(n - 1) >= threshold)
    return SG_Y(n - 1);
  for (sluice_index i = n - 1; i-- > 0;)
    if (SG_S(i) >= threshold)
      return SG_Y(i) + (SG_S(i) - threshold) / (SG_S(i) - SG_S(i + 1)) *
                           (SG_Y(i + 1) - SG_Y(i));
  return NAN;
#undef SG_S
#undef SG_Y
}

#endif

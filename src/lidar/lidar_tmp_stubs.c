/* TEMPORARY (removed at the merge of the echoes branch) */
#include <stdlib.h>
#include <stdio.h>
#include "dartspp/lidar.h"
#include "dartspp/io.h"
double lidar_peak_reference(const lidar_params *l, double R) { (void)l; (void)R; return 1; }
int lidar_find_echoes(const float *wave, int bins, double range_bin, double threshold, lidar_echo_mode mode,
                      lidar_echo *out, int max_out) { (void)wave; (void)bins; (void)range_bin; (void)threshold; (void)mode; (void)out; (void)max_out; return 0; }
int lidar_points_from_waveforms(const lidar_params *l, vec3 origin, vec3 forward, vec3 left, vec3 up,
                                const float *waveforms, lidar_points *pts, dp_error *err)
{ (void)l; (void)origin; (void)forward; (void)left; (void)up; (void)waveforms; (void)err; pts->rows = NULL; pts->count = 0; return 0; }
void lidar_points_free(lidar_points *pts) { free(pts->rows); }
int lidar_points_write_ply(const char *path, const lidar_points *pts, dp_error *err) { (void)pts; atomic_file af; FILE *f = atomic_fopen(path, "w", &af, err); if (!f) return -1; fprintf(f, "ply\n"); return atomic_fclose(&af, 0, err); }
int lidar_waveforms_sidecar_write(const char *path, const lidar_params *l, dp_error *err) { (void)l; atomic_file af; FILE *f = atomic_fopen(path, "w", &af, err); if (!f) return -1; fprintf(f, "{}\n"); return atomic_fclose(&af, 0, err); }

/* Integrator and renderer keys, the time window, and `--set key=value` overrides. Internal. */
#ifndef DARTSPP_SCENE_SETTINGS_H
#define DARTSPP_SCENE_SETTINGS_H

#include "scene_internal.h"

/* Applies "key=value" overrides to root.renderer when key is a renderer key, else to root.integrator. */
int settings_apply_overrides(json_ctx *c, cJSON *root, const char *const *sets, int count);
int settings_parse(json_ctx *c, const cJSON *root, scene *s);
/* Tungsten duration strings: a bare number means minutes; suffixes ms, s, m, h, d. -1 on a bad string. */
double parse_duration_seconds(const char *text);

#endif

/* Typed reads of scene-file values with error messages that name the file, the key and the reason.
 * Internal to the scene module. */
#ifndef DARTSPP_SCENE_JSON_READ_H
#define DARTSPP_SCENE_JSON_READ_H

#include <cjson/cJSON.h>

#include "dartspp/core.h"

typedef struct {
    char *text;
    size_t len, cap;
} strbuf;

void strbuf_addf(strbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

typedef struct {
    const char *file;   /* scene file, for messages */
    dp_error *err;
    int verbose;        /* list ignored keys */
    strbuf *notes;      /* warnings and ignored keys */
} json_ctx;

/* Each getter leaves *out = def when the key is absent and returns 0; on a present but bad value it
 * returns -1 with "<file>: <where>.<key>: <reason>" in ctx->err. `where` is the object's path. */
int jget_number(json_ctx *c, const cJSON *obj, const char *where, const char *key, double def, double *out);
int jget_int(json_ctx *c, const cJSON *obj, const char *where, const char *key, long def, long *out);
int jget_bool(json_ctx *c, const cJSON *obj, const char *where, const char *key, int def, int *out);
int jget_vec3(json_ctx *c, const cJSON *obj, const char *where, const char *key, vec3 def, vec3 *out);
/* string value; returns 1 when present, 0 when absent (out untouched), -1 when not a string */
int jget_string(json_ctx *c, const cJSON *obj, const char *where, const char *key, const char **out);
/* Like jget_number but also requires lo <= value (and value <= hi when hi > lo). */
int jget_number_range(json_ctx *c, const cJSON *obj, const char *where, const char *key, double def, double lo,
                      double hi, double *out);
/* Notes keys of obj that are not in the NULL-terminated list `known` (only with ctx->verbose). */
void jnote_unknown_keys(json_ctx *c, const cJSON *obj, const char *where, const char *const *known);
int jfail(json_ctx *c, const char *where, const char *key, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
void jwarn(json_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif

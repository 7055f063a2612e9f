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
    /* the members read so far (jget_item), so that the keys nobody read can be listed: no list of known
     * keys is kept anywhere, a key is known where it is read */
    const cJSON **read;
    size_t read_len, read_cap;
    int read_lost;      /* out of memory while recording: list nothing rather than wrong keys */
} json_ctx;

void json_ctx_free(json_ctx *c);

/* The member `key` of obj (NULL when absent or obj is NULL), recorded as read. Every getter below reads
 * through it. */
const cJSON *jget_item(json_ctx *c, const cJSON *obj, const char *key);
/* Where the members read from now on start; pass it to jnote_unread_keys once the object is parsed. */
size_t jread_mark(const json_ctx *c);
/* With verbose: notes each member of obj that was not read since mark ("ignored key: <where>.<key>"); then
 * forgets what was read since mark. Call it after the object's last read. */
void jnote_unread_keys(json_ctx *c, const cJSON *obj, const char *where, size_t mark);

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
int jfail(json_ctx *c, const char *where, const char *key, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
void jwarn(json_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif

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
    /* every key asked for so far (jget_item) and the member found (NULL when absent), so that the keys nobody
     * read can be listed and a misspelt one matched to the key meant: no list of known keys is kept anywhere,
     * a key is known where it is read */
    struct json_asked { const char *key; const cJSON *item; } *read;
    size_t read_len, read_cap;
    int read_lost;      /* out of memory while recording: list nothing rather than wrong keys */
} json_ctx;

void json_ctx_free(json_ctx *c);

/* The member `key` of obj (NULL when absent or obj is NULL), recorded as read. Every getter below reads
 * through it. */
const cJSON *jget_item(json_ctx *c, const cJSON *obj, const char *key);
/* Where the members read from now on start; pass it to jnote_unread_keys once the object is parsed. */
size_t jread_mark(const json_ctx *c);
/* Each member of obj that was not read since mark: a warning when it is a few edits from a key asked for since
 * mark (key_suggest.c: "unknown key "emmision" (did you mean "emission"?)") or repeats one, else with verbose a
 * note ("ignored key: <where>.<key>"); then forgets what was read since mark. Call it after the object's last
 * read. */
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

/* key_suggest.c: the known key nearest to a member nobody read, when it is close enough to be a misspelling. */
typedef struct {
    const char *best; /* NULL: none close enough */
    int dist;
} key_near;
void key_near_consider(key_near *n, const char *key, const char *known);
/* The warning for key in the object at where, when n found a key close to it (nothing otherwise). */
void jwarn_unknown_key(json_ctx *c, const char *where, const char *key, const key_near *n);

#endif

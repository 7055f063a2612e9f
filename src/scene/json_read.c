/* Typed reads of scene-file values (cJSON) with messages naming file, key and reason. */
#include "json_read.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void strbuf_addf(strbuf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if (b->len + (size_t)n + 2 > b->cap) {
        size_t cap = (b->cap ? b->cap * 2 : 256) + (size_t)n + 2;
        char *t = realloc(b->text, cap);
        if (!t) return;
        b->text = t;
        b->cap = cap;
    }
    va_start(ap, fmt);
    vsnprintf(b->text + b->len, b->cap - b->len, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
    b->text[b->len++] = '\n';
    b->text[b->len] = 0;
}

int jfail(json_ctx *c, const char *where, const char *key, const char *fmt, ...)
{
    char reason[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    if (key)
        return dp_fail(c->err, "%s: %s%s%s: %s", c->file, where, where[0] ? "." : "", key, reason);
    return dp_fail(c->err, "%s: %s: %s", c->file, where, reason);
}

void jwarn(json_ctx *c, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (c->notes) strbuf_addf(c->notes, "warning: %s: %s", c->file, msg);
}

/* Counts such as `7e5` may be written as floats; numbers written as strings ("1e6") are accepted too. */
static int as_number(const cJSON *v, double *out)
{
    if (cJSON_IsNumber(v)) {
        *out = v->valuedouble;
        return 1;
    }
    if (cJSON_IsBool(v)) {
        *out = cJSON_IsTrue(v) ? 1.0 : 0.0;
        return 1;
    }
    if (cJSON_IsString(v) && v->valuestring[0]) {
        char *end;
        double d = strtod(v->valuestring, &end);
        if (*end == 0) {
            *out = d;
            return 1;
        }
    }
    return 0;
}

int jget_number(json_ctx *c, const cJSON *obj, const char *where, const char *key, double def, double *out)
{
    const cJSON *v = jget_item(c, obj, key);
    *out = def;
    if (!v) return 0;
    double d;
    if (!as_number(v, &d)) return jfail(c, where, key, "expected a number");
    if (!isfinite(d)) return jfail(c, where, key, "must be finite (got %g)", d);
    *out = d;
    return 0;
}

int jget_number_range(json_ctx *c, const cJSON *obj, const char *where, const char *key, double def, double lo,
                      double hi, double *out)
{
    if (jget_number(c, obj, where, key, def, out)) return -1;
    if (*out < lo) return jfail(c, where, key, "must be >= %g (got %g)", lo, *out);
    if (hi > lo && *out > hi) return jfail(c, where, key, "must be <= %g (got %g)", hi, *out);
    return 0;
}

int jget_int(json_ctx *c, const cJSON *obj, const char *where, const char *key, long def, long *out)
{
    double d;
    if (jget_number(c, obj, where, key, (double)def, &d)) return -1;
    if (d > 2e18 || d < -2e18) return jfail(c, where, key, "out of range (got %g)", d);
    *out = (long)llround(d);
    return 0;
}

int jget_bool(json_ctx *c, const cJSON *obj, const char *where, const char *key, int def, int *out)
{
    const cJSON *v = jget_item(c, obj, key);
    *out = def;
    if (!v) return 0;
    if (cJSON_IsBool(v)) *out = cJSON_IsTrue(v);
    else if (cJSON_IsNumber(v)) *out = v->valuedouble != 0.0;
    else if (cJSON_IsString(v) && (!strcmp(v->valuestring, "true") || !strcmp(v->valuestring, "false")))
        *out = !strcmp(v->valuestring, "true");
    else return jfail(c, where, key, "expected true or false");
    return 0;
}

int jget_vec3(json_ctx *c, const cJSON *obj, const char *where, const char *key, vec3 def, vec3 *out)
{
    const cJSON *v = jget_item(c, obj, key);
    *out = def;
    if (!v) return 0;
    double d;
    if (as_number(v, &d)) {
        if (!isfinite(d)) return jfail(c, where, key, "must be finite (got %g)", d);
        *out = v3s(d);
        return 0;
    }
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3)
        return jfail(c, where, key, "expected a number or an array of 3 numbers");
    double e[3];
    for (int i = 0; i < 3; i++) {
        if (!as_number(cJSON_GetArrayItem(v, i), &e[i]))
            return jfail(c, where, key, "element %d is not a number", i);
        if (!isfinite(e[i])) return jfail(c, where, key, "element %d must be finite (got %g)", i, e[i]);
    }
    *out = v3(e[0], e[1], e[2]);
    return 0;
}

int jget_string(json_ctx *c, const cJSON *obj, const char *where, const char *key, const char **out)
{
    const cJSON *v = jget_item(c, obj, key);
    if (!v) return 0;
    if (!cJSON_IsString(v)) return jfail(c, where, key, "expected a string");
    *out = v->valuestring;
    return 1;
}

const cJSON *jget_item(json_ctx *c, const cJSON *obj, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!obj || c->read_lost) return v;
    if (c->read_len == c->read_cap) {
        size_t cap = c->read_cap ? 2 * c->read_cap : 64;
        struct json_asked *grown = realloc(c->read, cap * sizeof *grown);
        if (!grown) {
            c->read_lost = 1;
            return v;
        }
        c->read = grown;
        c->read_cap = cap;
    }
    c->read[c->read_len++] = (struct json_asked){key, v};
    return v;
}

size_t jread_mark(const json_ctx *c)
{
    return c->read_len;
}

void jnote_unread_keys(json_ctx *c, const cJSON *obj, const char *where, size_t mark)
{
    if (mark > c->read_len) mark = c->read_len;
    for (const cJSON *it = cJSON_IsObject(obj) ? obj->child : NULL; it && c->notes && !c->read_lost; it = it->next) {
        int read = 0;
        for (size_t i = mark; i < c->read_len && !read; i++) read = c->read[i].item == it;
        if (read) continue;
        key_near n = {0};
        for (size_t i = mark; i < c->read_len; i++) key_near_consider(&n, it->string, c->read[i].key);
        if (n.best) jwarn_unknown_key(c, where, it->string, &n);
        else if (c->verbose) strbuf_addf(c->notes, "ignored key: %s%s%s", where, where[0] ? "." : "", it->string);
    }
    c->read_len = mark;
}

void json_ctx_free(json_ctx *c)
{
    free(c->read);
    c->read = NULL;
    c->read_len = c->read_cap = 0;
}

/* Misspelt keys: a member of a scene object that nothing read but that is a few edits from a key the object's
 * reader asked for ("emmision" beside "emission") is a warning naming the object and that key. The known keys
 * are the reader's own queries (json_read.c records every key asked for, present or not) or the key table's
 * rows (settings.c), never a second hand-written list. A member far from every known key stays a note with
 * --verbose: the paper's Tungsten files carry keys dartspp does not read, and those are not mistakes. */
#include <ctype.h>
#include <string.h>

#include "json_read.h"

/* Edit distance with adjacent transpositions (optimal string alignment), letters compared without case; keys
 * longer than 63 characters are never close to anything. */
static int key_distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    if (n > 63 || m > 63) return 1 << 20;
    int d[64][64];
    for (size_t i = 0; i <= n; i++) d[i][0] = (int)i;
    for (size_t j = 0; j <= m; j++) d[0][j] = (int)j;
    for (size_t i = 1; i <= n; i++)
        for (size_t j = 1; j <= m; j++) {
            int cost = tolower((unsigned char)a[i - 1]) != tolower((unsigned char)b[j - 1]);
            int v = d[i - 1][j - 1] + cost;
            if (d[i - 1][j] + 1 < v) v = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
            if (i > 1 && j > 1 && tolower((unsigned char)a[i - 1]) == tolower((unsigned char)b[j - 2]) &&
                tolower((unsigned char)a[i - 2]) == tolower((unsigned char)b[j - 1]) && d[i - 2][j - 2] + 1 < v)
                v = d[i - 2][j - 2] + 1;
            d[i][j] = v;
        }
    return d[n][m];
}

/* How many edits still read as a misspelling of a key of this length: one for short keys, two from six
 * letters on (so "emmision" finds "emission", but "type" does not find "size"). */
static int close_enough(size_t len)
{
    return len >= 6 ? 2 : 1;
}

void key_near_consider(key_near *n, const char *key, const char *known)
{
    if (!key || !known) return;
    int d = key_distance(key, known);
    size_t len = strlen(known) > strlen(key) ? strlen(known) : strlen(key);
    if (d > close_enough(len)) return;
    if (!n->best || d < n->dist) {
        n->best = known;
        n->dist = d;
    }
}

void jwarn_unknown_key(json_ctx *c, const char *where, const char *key, const key_near *n)
{
    const char *dot = where[0] ? "." : "";
    if (n->best && strcmp(n->best, key) == 0)
        jwarn(c, "%s%s%s: the key is given twice; the first value is read, this one ignored", where, dot, key);
    else if (n->best)
        jwarn(c, "%s: unknown key \"%s\" (did you mean \"%s\"?); it is ignored", where[0] ? where : "(top level)",
              key, n->best);
}

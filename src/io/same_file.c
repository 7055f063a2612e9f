/* Whether two paths name one file, and the refusal of an output that would replace an input: every command
 * that writes calls io_refuse_output_over_input before any work. Names are not enough — a hard link, a
 * symlink, "./x" or "dir/../x" reach the same file under another name — so an existing file is compared by
 * device and inode, and a file that does not exist yet by its resolved folder and name. */
#include "dartspp/io.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

/* The absolute, link-free name of a path: realpath of the file when it exists, else realpath of its folder
 * plus its last name (a file about to be written). 0, or -1 when not even the folder exists. */
static int resolved_name(const char *path, char *out, size_t n)
{
    char buf[PATH_MAX];
    if (realpath(path, buf)) return snprintf(out, n, "%s", buf) < (int)n ? 0 : -1;
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == path) snprintf(dir, sizeof dir, "/");
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    const char *base = slash ? slash + 1 : path;
    if (!*base || !strcmp(base, ".") || !strcmp(base, "..") || !realpath(dir, buf)) return -1;
    return snprintf(out, n, "%s/%s", strcmp(buf, "/") ? buf : "", base) < (int)n ? 0 : -1;
}

/* The path with "." and "name/.." removed by its text alone. Right for a path under folders that do not exist
 * yet (io_make_parent_dirs will create them as plain folders: no link can make ".." go elsewhere), where the
 * kernel cannot resolve it: "new/../ref.exr" names ref.exr once "new" is made. */
static void lexical_normal(const char *path, char *out, size_t n)
{
    char buf[PATH_MAX];
    snprintf(buf, sizeof buf, "%s", path);
    const char *parts[PATH_MAX / 2];
    int k = 0;
    for (char *save = NULL, *p = strtok_r(buf, "/", &save); p && k < PATH_MAX / 2; p = strtok_r(NULL, "/", &save)) {
        if (!strcmp(p, ".")) continue;
        if (!strcmp(p, "..") && k > 0 && strcmp(parts[k - 1], "..")) k--;
        else parts[k++] = p;
    }
    size_t used = (size_t)snprintf(out, n, "%s", path[0] == '/' ? "/" : (k ? "" : "."));
    for (int i = 0; i < k && used < n; i++) used += (size_t)snprintf(out + used, n - used, "%s%s", i ? "/" : "", parts[i]);
}

/* stat of an output: of its path, or when that fails (a folder on the way does not exist yet), of the path
 * with its "name/.." removed. */
static int stat_output(const char *path, struct stat *st)
{
    if (stat(path, st) == 0) return 0;
    char normal[PATH_MAX];
    lexical_normal(path, normal, sizeof normal);
    return strcmp(normal, path) ? stat(normal, st) : -1;
}

int io_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    int ea = stat(a, &sa) == 0, eb = stat(b, &sb) == 0;
    if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    if (ea != eb) return 0; /* a name that does not exist is not a file that does */
    /* neither exists (two outputs): the same resolved name */
    char ra[PATH_MAX + 256], rb[PATH_MAX + 256];
    if (resolved_name(a, ra, sizeof ra) || resolved_name(b, rb, sizeof rb)) return !strcmp(a, b);
    return !strcmp(ra, rb);
}

int io_refuse_output_over_input(const io_file *outputs, int n_out, const io_file *inputs, int n_in, dp_error *err)
{
    /* An output that does not exist yet cannot be an input that does (and an input that does not exist is
     * refused by its reader): only existing pairs are compared, each path stat'ed once, so that the frames of a
     * long render (up to 100,000 names) cost one stat each. */
    struct stat *in = malloc((size_t)(n_in > 0 ? n_in : 1) * sizeof *in);
    char *exists = calloc((size_t)(n_in > 0 ? n_in : 1), 1);
    if (!in || !exists) {
        free(in);
        free(exists);
        return dp_fail_kind(err, DP_ERROR_MEMORY, "out of memory");
    }
    for (int i = 0; i < n_in; i++) exists[i] = inputs[i].path && stat(inputs[i].path, &in[i]) == 0;
    int rc = 0;
    for (int o = 0; o < n_out && !rc; o++) {
        struct stat st;
        if (!outputs[o].path || stat_output(outputs[o].path, &st) != 0) continue;
        for (int i = 0; i < n_in && !rc; i++)
            if (exists[i] && in[i].st_dev == st.st_dev && in[i].st_ino == st.st_ino)
                rc = dp_fail(err, "the output %s (%s) is the input %s (%s): it would be overwritten; write to "
                                  "another path", outputs[o].path, outputs[o].what, inputs[i].path, inputs[i].what);
    }
    free(in);
    free(exists);
    return rc;
}

int io_has_extension(const char *path, const char *ext)
{
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    size_t n = strlen(base), e = strlen(ext);
    return n > e && strcasecmp(base + n - e, ext) == 0;
}

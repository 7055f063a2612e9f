/* tier: quick */
/* Every source file is named in its module's README (issue 47): a newcomer finds a file through that table.
 * Every section a comment cites resolves inside a clone (issue 31). The test lists each "§" in the text files
 * of src/, include/, tests/, bench/ and in README.md, and checks it (the rules are also in docs/README.md):
 * - `docs/time.md §2.2`: a path from the repository root ending in .md, then the section number. The file
 *   must exist and have a Markdown heading whose text begins with that number (`### 2.2 Unwarped ...`;
 *   `§2` finds `## 2. Camera-warped ...` but not `## 2.2 ...` nor `## 20 ...`).
 * - A § right after a separator (`, §9.3`, `and §5`, `(§6)`) takes the file of the citation before it on
 *   the same line; with none before it, it names no file and fails.
 * - A § right after the name of a published work (WORKS below) is that work's own numbering: not checked.
 * - Anything else (`DESIGN §4`, `reference §6`, `transient-math.md §1.4` without its folder) fails, naming
 *   file:line and the citation: it refers to nothing a clone of the repository has.
 * This file itself is not scanned: its examples are broken on purpose. Run from the repository root, as
 * tests/run_tests.sh does. */
#include "child_process.h"
#include "test_util.h"

#include <ctype.h>
#include <dirent.h>

/* Published works cited by their own section numbers; the text before the § must end with one of these. */
static const char *const WORKS[] = {
    "paper",            /* the DARTS paper, He et al., TOG 43(6) 2024 */
    "supplement",       /* its supplementary note */
    "Veach 1997",       /* Veach's thesis */
    "Walter",           /* Walter et al. 2007, microfacet models for refraction */
    "Walter et al. 2007",
    "Principles of Optics", /* Born & Wolf */
    "pbrt-v3",
    "Numerical Recipes",
    "Jarabo et al. 2014", /* "A framework for transient rendering", TOG 33(6) */
    "TAOCP vol. 2",     /* Knuth, The Art of Computer Programming, vol. 2, Seminumerical Algorithms */
    "Liu et al. 2022",  /* temporally sliced photon primitives, CGF 41(4) (EGSR) 2022 */
};

static const char *const ROOTS[] = {"src", "include", "tests", "bench", "README.md"};
static const char *const EXTENSIONS[] = {".c", ".h", ".md", ".sh", ".py"};

typedef struct {
    int citations; /* § resolved to a file of the repository */
    int works;     /* § of a published work */
    int failures;
    int quiet;     /* count failures without printing them */
} cite_count;

static int ends_with(const char *s, size_t n, const char *suffix)
{
    size_t k = strlen(suffix);
    return n >= k && !memcmp(s + n - k, suffix, k);
}

/* Whether the Markdown file has a heading (outside code fences) whose text begins with the number num:
 * num followed by the end of the line, a space, or a dot that ends the number. -1: the file cannot be read. */
static int heading_exists(const char *path, const char *num)
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[4096];
    int fence = 0, found = 0;
    size_t n = strlen(num);
    while (!found && fgets(line, sizeof line, f)) {
        if (!strncmp(line, "```", 3)) fence = !fence;
        if (fence || line[0] != '#') continue;
        const char *p = line;
        while (*p == '#') p++;
        if (*p != ' ') continue;
        while (*p == ' ') p++;
        if (strncmp(p, num, n)) continue;
        char c = p[n];
        found = c == '\0' || c == '\n' || c == ' ' || (c == '.' && (p[n + 1] == ' ' || p[n + 1] == '\n'));
    }
    fclose(f);
    return found;
}

static void report(cite_count *cc, const char *where, int lineno, const char *from, const char *to,
                   const char *why)
{
    if (!cc->quiet) print_message("%s:%d: '%.*s': %s\n", where, lineno, (int)(to - from), from, why);
    cc->failures++;
}

/* Checks the citations of one line of the file `where`; adds to cc. */
static void check_line(const char *where, int lineno, const char *line, cite_count *cc)
{
    enum { NONE, FILE_CITE, WORK } prev = NONE;
    char file[512] = "";
    const char *p = line, *s;
    while ((s = strstr(p, "§"))) {
        const char *num = s + strlen("§");
        size_t nl = strspn(num, "0123456789.");
        while (nl > 0 && num[nl - 1] == '.') nl--;
        p = num + nl;
        const char *b = s; /* the token before the §: [a, b) */
        while (b > line && b[-1] == ' ') b--;
        const char *a = b;
        while (a > line && !isspace((unsigned char)a[-1])) a--;
        const char *t = a;
        while (t < b && strchr("([`\"'*", *t)) t++;
        int kind = NONE;
        if (ends_with(t, (size_t)(b - t), ".md")) {
            if ((size_t)(b - t) >= sizeof file) {
                report(cc, where, lineno, t, p, "path too long");
                continue;
            }
            memcpy(file, t, (size_t)(b - t));
            file[b - t] = '\0';
            kind = FILE_CITE;
        } else {
            for (size_t w = 0; w < sizeof WORKS / sizeof *WORKS && kind == NONE; w++) {
                size_t k = strlen(WORKS[w]);
                if (ends_with(line, (size_t)(b - line), WORKS[w]) &&
                    (b - line == (ptrdiff_t)k || !isalnum((unsigned char)b[-(ptrdiff_t)k - 1])))
                    kind = WORK;
            }
            int separated = b > line && strchr(",;(/", b[-1]);
            if (kind == NONE && prev != NONE && (separated || ((b - t == 3 && !strncmp(t, "and", 3)) ||
                                                                (b - t == 2 && !strncmp(t, "or", 2)))))
                kind = prev; /* `docs/x.md §1, §2`: the same file */
        }
        prev = kind;
        if (kind == NONE) {
            report(cc, where, lineno, t, p, "names no file of the repository (write docs/<file>.md §N)");
            continue;
        }
        if (kind == WORK) {
            cc->works++;
            continue;
        }
        cc->citations++;
        char sec[64];
        if (nl == 0 || nl >= sizeof sec) {
            report(cc, where, lineno, t, p, "no section number after the §");
            continue;
        }
        memcpy(sec, num, nl);
        sec[nl] = '\0';
        int h = heading_exists(file, sec);
        char why[700];
        if (h < 0) snprintf(why, sizeof why, "%s does not exist", file);
        else if (!h) snprintf(why, sizeof why, "%s has no heading %s", file, sec);
        if (h <= 0) report(cc, where, lineno, t, p, why);
    }
}

static void check_file(const char *path, cite_count *cc)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[8192];
    int lineno = 0;
    while (fgets(line, sizeof line, f)) check_line(path, ++lineno, line, cc);
    fclose(f);
}

typedef struct {
    char **paths;
    size_t n, cap;
} path_list;

static void add_path(path_list *out, const char *path)
{
    if (out->n == out->cap) {
        out->cap = out->cap ? 2 * out->cap : 256;
        out->paths = realloc(out->paths, out->cap * sizeof *out->paths);
        assert_non_null(out->paths);
    }
    out->paths[out->n++] = strdup(path);
}

/* The text files under dir (or dir itself when it is a file). */
static void list_files(const char *dir, path_list *out)
{
    DIR *d = opendir(dir);
    if (!d) {
        if (!access(dir, R_OK)) add_path(out, dir);
        return;
    }
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat st;
        if (stat(path, &st)) continue;
        if (S_ISDIR(st.st_mode)) {
            list_files(path, out);
            continue;
        }
        int text = 0;
        for (size_t k = 0; k < sizeof EXTENSIONS / sizeof *EXTENSIONS; k++)
            text |= ends_with(path, strlen(path), EXTENSIONS[k]);
        /* this file's own examples are broken on purpose (test_checker_on_known_lines) */
        if (!S_ISREG(st.st_mode) || !text || !strcmp(path, "tests/cli/test_docs.c")) continue;
        add_path(out, path);
    }
    closedir(d);
}

static int compare_paths(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The checker itself, on lines whose verdict is known (it reads the repository's docs/time.md and
 * docs/darts.md). Each broken form must fail, or the scan below could pass by not looking. */
static void test_checker_on_known_lines(void **state)
{
    (void)state;
    static const struct {
        const char *line;
        int citations, works, failures;
    } cases[] = {
        {"/* time (docs/time.md §2.2) */", 1, 0, 0},
        {"/* (docs/darts.md §3 and §5; paper §5.2, eq. 19–22) */", 2, 1, 0},
        {" * o + t·d (docs/reference-renderer.md §8.4, §9.3). */", 2, 0, 0},
        {" * docs/scene-format.md §1 (.wo3), §2.2 (transform) and §2.5 (quad, cube) */", 3, 0, 0},
        {"/* Veach 1997 §5.2-5.3 and Walter et al. 2007 §5.3 */", 0, 2, 0},
        {"- `docs/time.md §2` and `docs/time.md §2.`", 2, 0, 0},
        {"/* bounces (DESIGN §4) */", 0, 0, 1},
        {"/* reference §6 check case */", 0, 0, 1},
        {"/* W = σs e^{−σt t}/p(t) (§6) */", 0, 0, 1},
        {"/* transient-math.md §1.4 */", 1, 0, 1},
        {"/* docs/time.md §99 */", 1, 0, 1},
        {"/* docs/time.md §20 */", 1, 0, 1},
        {"/* docs/time.md §2.2.1 */", 1, 0, 1},
        {"/* docs/nothing.md §1 */", 1, 0, 1},
        {"/* docs/time.md §2, §99 */", 2, 0, 1},
        {"/* docs/time.md § */", 1, 0, 1},
        {"/* see the paper. §3 */", 0, 0, 1},
    };
    int bad = 0;
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        cite_count cc = {.quiet = 1};
        check_line("(case)", (int)i + 1, cases[i].line, &cc);
        if (cc.citations != cases[i].citations || cc.works != cases[i].works || cc.failures != cases[i].failures) {
            print_message("case %zu \"%s\": %d citations, %d works, %d failures; expected %d, %d, %d\n", i + 1,
                          cases[i].line, cc.citations, cc.works, cc.failures, cases[i].citations, cases[i].works,
                          cases[i].failures);
            bad++;
        }
    }
    assert_int_equal(bad, 0);
}

static void test_every_citation_resolves(void **state)
{
    (void)state;
    assert_true(access("docs/README.md", R_OK) == 0); /* run from the repository root */
    path_list files = {0};
    for (size_t r = 0; r < sizeof ROOTS / sizeof *ROOTS; r++) list_files(ROOTS[r], &files);
    qsort(files.paths, files.n, sizeof *files.paths, compare_paths);
    cite_count cc = {0};
    for (size_t i = 0; i < files.n; i++) {
        check_file(files.paths[i], &cc);
        free(files.paths[i]);
    }
    free(files.paths);
    print_message("  %zu files: %d citations of the repository's documents, %d of published works, %d failing\n",
                  files.n, cc.citations, cc.works, cc.failures);
    assert_true(files.n > 100);     /* the scan saw the tree */
    assert_true(cc.citations >= 40); /* the code cites the docs about 60 times: far fewer means a broken scan */
    assert_int_equal(cc.failures, 0);
}

/* The .c and .h files of each module folder under root (root/<module>/) whose name its README.md does not
 * contain, each printed; a folder without a README counts all its files. */
static int unlisted_sources(const char *root, int *modules)
{
    DIR *d = opendir(root);
    assert_non_null(d);
    int unlisted = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        char dir[4096], readme[4200];
        struct stat st;
        snprintf(dir, sizeof dir, "%s/%s", root, e->d_name);
        if (e->d_name[0] == '.' || stat(dir, &st) || !S_ISDIR(st.st_mode)) continue;
        snprintf(readme, sizeof readme, "%s/README.md", dir);
        char *text = read_text(readme); /* "" when there is no README */
        (*modules)++;
        DIR *m = opendir(dir);
        assert_non_null(m);
        struct dirent *f;
        while ((f = readdir(m))) {
            size_t n = strlen(f->d_name);
            if (!(ends_with(f->d_name, n, ".c") || ends_with(f->d_name, n, ".h"))) continue;
            if (strstr(text, f->d_name)) continue;
            print_message("  %s/%s is not named in %s\n", dir, f->d_name, readme);
            unlisted++;
        }
        closedir(m);
        free(text);
    }
    closedir(d);
    return unlisted;
}

/* The check on a made-up tree: a module whose README names one of its two files, and one without a README. */
static void test_readme_checker_on_a_known_tree(void **state)
{
    (void)state;
    char *root = test_tmpdir();
    assert_non_null(root);
    char path[4096];
    const char *files[][2] = {{"a/README.md", "| `one.c` | the first |\n"}, {"a/one.c", ""}, {"a/two.h", ""},
                              {"b/three.c", ""}};
    snprintf(path, sizeof path, "%s/a", root);
    assert_int_equal(mkdir(path, 0755), 0);
    snprintf(path, sizeof path, "%s/b", root);
    assert_int_equal(mkdir(path, 0755), 0);
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        snprintf(path, sizeof path, "%s/%s", root, files[i][0]);
        FILE *f = fopen(path, "w");
        assert_non_null(f);
        fputs(files[i][1], f);
        fclose(f);
    }
    int modules = 0;
    assert_int_equal(unlisted_sources(root, &modules), 2); /* two.h, and three.c of the folder without README */
    assert_int_equal(modules, 2);
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        snprintf(path, sizeof path, "%s/%s", root, files[i][0]);
        unlink(path);
    }
    snprintf(path, sizeof path, "%s/a", root);
    rmdir(path);
    snprintf(path, sizeof path, "%s/b", root);
    rmdir(path);
    rmdir(root);
    free(root);
}

static void test_every_source_file_in_its_readme(void **state)
{
    (void)state;
    int modules = 0;
    int unlisted = unlisted_sources("src", &modules);
    print_message("  %d module folders in src/, %d source files not named in their README\n", modules, unlisted);
    assert_true(modules >= 15); /* the scan saw the tree */
    assert_int_equal(unlisted, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_readme_checker_on_a_known_tree),
        cmocka_unit_test(test_every_source_file_in_its_readme),
        cmocka_unit_test(test_checker_on_known_lines),
        cmocka_unit_test(test_every_citation_resolves),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

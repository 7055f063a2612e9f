/* tier: quick */
/* Atomic writes of the io module (a temp file renamed into place): no temp file left behind, missing folders
 * and make_parent_dirs, a failed write (file size limit) keeping the old file, open/commit/abort and the
 * fopen/fclose/fabort pair; and the frame CSV. */
#include "fixtures.h"

#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>

/* ---- atomic writes ---- */

static void test_atomic_no_temp_left(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err;
    fill(&img, 3, 2, special);
    const char *names[] = {"a.exr", "a.pfm", "a.png", "a.csv"};
    for (int round = 0; round < 2; ++round) { /* the second round overwrites */
        join(path, sizeof path, dir, names[0]);
        assert_int_equal(exr_write(path, &img, NULL, &err), 0);
        join(path, sizeof path, dir, names[1]);
        assert_int_equal(pfm_write(path, &img, &err), 0);
        join(path, sizeof path, dir, names[2]);
        assert_int_equal(png_write_preview(path, &img, &err), 0);
        join(path, sizeof path, dir, names[3]);
        assert_int_equal(frames_csv_write(path, 2, 0.0, 1.0, &err), 0);
    }
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        assert_true(file_size(path) > 0);
    }
    assert_int_equal(count_temp_files(dir), 0);
    image_free(&img);
    test_rmtree(dir);
}

static void test_atomic_missing_folder_and_make_parent_dirs(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err = {0};
    fill(&img, 3, 2, special);
    const char *names[] = {"x/y/z/a.exr", "x/y/z/a.pfm", "x/y/z/a.png", "x/y/z/a.csv"};
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        err.msg[0] = 0;
        int rc = i == 0   ? exr_write(path, &img, NULL, &err)
                 : i == 1 ? pfm_write(path, &img, &err)
                 : i == 2 ? png_write_preview(path, &img, &err)
                          : frames_csv_write(path, 1, 0.0, 1.0, &err);
        assert_int_not_equal(rc, 0);
        assert_non_null(strstr(err.msg, path));
        assert_non_null(strstr(err.msg, "No such file or directory"));
    }
    join(path, sizeof path, dir, names[1]);
    assert_int_equal(io_make_parent_dirs(path, &err), 0);
    assert_int_equal(io_make_parent_dirs(path, &err), 0); /* already there */
    assert_int_equal(pfm_write(path, &img, &err), 0);
    assert_int_equal(count_temp_files(dir), 0);
    /* a file where a folder should be */
    join(path, sizeof path, dir, "x/y/z/a.pfm/b/c.exr");
    assert_int_not_equal(io_make_parent_dirs(path, &err), 0);
    assert_non_null(strstr(err.msg, path));
    image_free(&img);
    test_rmtree(dir);
}

/* A write that fails half-way (file size limit) reports the path, leaves the old file untouched
 * and removes its temporary file. */
static void test_atomic_failed_write_keeps_old_file(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    image_rgb img;
    dp_error err = {0};
    noise_image(&img, 64, 64); /* 48 KiB of pixels */
    const char *names[] = {"f.exr", "f.pfm", "f.png", "f.csv"};
    long before[4];
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        test_write_file(path, "old");
        before[i] = file_size(path);
    }
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    lim = old;
    lim.rlim_cur = 4096;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    int rc[4];
    dp_error msgs[4];
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        rc[i] = i == 0   ? exr_write(path, &img, NULL, &msgs[i])
                : i == 1 ? pfm_write(path, &img, &msgs[i])
                : i == 2 ? png_write_preview(path, &img, &msgs[i])
                         : frames_csv_write(path, 1000, 0.0, 1.0, &msgs[i]);
    }
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, old_handler);
    for (int i = 0; i < 4; ++i) {
        join(path, sizeof path, dir, names[i]);
        assert_int_not_equal(rc[i], 0);
        assert_non_null(strstr(msgs[i].msg, path));
        assert_int_equal(file_size(path), before[i]);
    }
    assert_int_equal(count_temp_files(dir), 0);
    (void)err;
    image_free(&img);
    test_rmtree(dir);
}

static void test_atomic_open_commit_abort(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512], tmp[600];
    dp_error err;
    join(path, sizeof path, dir, "f.txt");
    int fd = atomic_open(path, tmp, sizeof tmp, &err);
    assert_true(fd >= 0);
    assert_non_null(strstr(tmp, ".tmp."));
    assert_int_equal(write(fd, "abc", 3), 3);
    atomic_abort(fd, tmp);
    assert_int_equal(file_size(path), -1);
    assert_int_equal(file_size(tmp), -1);
    fd = atomic_open(path, tmp, sizeof tmp, &err);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, "hello", 5), 5);
    assert_int_equal(file_size(path), -1); /* not visible before the commit */
    assert_int_equal(atomic_commit(fd, tmp, path, &err), 0);
    assert_int_equal(file_size(path), 5);
    assert_int_equal(file_size(tmp), -1);
    test_rmtree(dir);
}

/* The stream form: nothing visible before the close, nothing left by an abort or a failed write. */
static void test_atomic_fopen_fclose_fabort(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    dp_error err = {0};
    atomic_file af;
    join(path, sizeof path, dir, "s.txt");
    FILE *f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("abc", f) >= 0, 1);
    atomic_fabort(&af);
    assert_int_equal(file_size(path), -1);
    assert_int_equal(count_temp_files(dir), 0);
    f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("hello", f) >= 0, 1);
    assert_int_equal(atomic_fclose(&af, 1, &err), -1); /* the caller's write failed */
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "write failed"));
    assert_int_equal(file_size(path), -1);
    assert_int_equal(count_temp_files(dir), 0);
    f = atomic_fopen(path, "w", &af, &err);
    assert_non_null(f);
    assert_int_equal(fputs("hello", f) >= 0, 1);
    assert_int_equal(file_size(path), -1); /* not visible before the close */
    assert_int_equal(atomic_fclose(&af, 0, &err), 0);
    assert_int_equal(file_size(path), 5);
    assert_int_equal(count_temp_files(dir), 0);
    join(path, sizeof path, dir, "no/such/s.txt");
    assert_null(atomic_fopen(path, "w", &af, &err));
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "No such file or directory"));
    test_rmtree(dir);
}

/* ---- frame CSV ---- */

static void test_frames_csv(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), path[512];
    join(path, sizeof path, dir, "frames.csv");
    dp_error err;
    char text[512];
    assert_int_equal(frames_csv_write(path, 3, 1.5, 0.25, &err), 0);
    text[read_into(path, (unsigned char *)text, sizeof text - 1)] = 0;
    assert_string_equal(text, "index,start,end\n0,1.5,1.75\n1,1.75,2\n2,2,2.25\n");
    /* 0.1 steps are not exact in binary: the printed values must parse back to the same doubles */
    assert_int_equal(frames_csv_write(path, 3, 0.1, 0.1, &err), 0);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(text, sizeof text, f));
    assert_string_equal(text, "index,start,end\n");
    int k, rows = 0;
    double s, e;
    while (fscanf(f, "%d,%lf,%lf\n", &k, &s, &e) == 3) {
        assert_int_equal(k, rows);
        assert_true(s == 0.1 + k * 0.1);
        assert_true(e == 0.1 + (k + 1) * 0.1);
        ++rows;
    }
    fclose(f);
    assert_int_equal(rows, 3);
    assert_int_not_equal(frames_csv_write(path, -1, 0.0, 1.0, &err), 0);
    test_rmtree(dir);
}

/* ---- file sets and what killed runs leave ---- */

static long dead_pid(void)
{
    pid_t p = fork();
    assert_true(p >= 0);
    if (p == 0) _exit(0);
    waitpid(p, NULL, 0);
    return (long)p; /* reaped: no process has it until the kernel hands it out again */
}

static int notes;
static void count_note(const char *msg)
{
    print_message("  note: %s\n", msg);
    notes++;
}

/* A set: nothing visible before the commit, every file in place after it and no staging folder left; an
 * aborted set leaves the old files. atomic_clean_stale removes the temporary file and the staging folder of
 * a process that no longer runs, completes its commit folder, and leaves a running process's (the parent
 * of this test) alone; a file of another stem is not touched. */
static void test_atomic_set_and_stale(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), stem[512], path[9000];
    dp_error err;
    atomic_set set;
    join(stem, sizeof stem, dir, "s");
    join(path, sizeof path, dir, "s_0000.txt");
    test_write_file(path, "old");
    assert_int_equal(atomic_set_open(&set, stem, &err), 0);
    snprintf(path, sizeof path, "%s_0000.txt", set.stem);
    test_write_file(path, "new0");
    snprintf(path, sizeof path, "%s_0001.txt", set.stem);
    test_write_file(path, "new1");
    join(path, sizeof path, dir, "s_0000.txt");
    assert_int_equal(file_size(path), 3); /* the old file until the commit */
    atomic_set_abort(&set);
    assert_int_equal(file_size(path), 3);
    assert_int_equal(file_size(set.stage), -1);
    assert_int_equal(atomic_set_open(&set, stem, &err), 0);
    snprintf(path, sizeof path, "%s_0000.txt", set.stem);
    test_write_file(path, "new0");
    snprintf(path, sizeof path, "%s_0001.txt", set.stem);
    test_write_file(path, "new1");
    assert_int_equal(atomic_set_commit(&set, NULL, &err), 0);
    join(path, sizeof path, dir, "s_0000.txt");
    assert_int_equal(file_size(path), 4);
    join(path, sizeof path, dir, "s_0001.txt");
    assert_int_equal(file_size(path), 4);
    assert_int_equal(count_temp_files(dir), 0);
    /* left behind by processes that are gone, one that runs, and another output's */
    long dead = dead_pid(), dead2 = dead_pid(), live = (long)getppid();
    char name[200];
    snprintf(name, sizeof name, "s_0001.txt.tmp.%ld", dead);
    join(path, sizeof path, dir, name);
    test_write_file(path, "half");
    snprintf(name, sizeof name, ".s.set.tmp.%ld", dead);
    join(path, sizeof path, dir, name);
    assert_int_equal(mkdir(path, 0755), 0);
    strcat(path, "/s_0000.txt");
    test_write_file(path, "staged");
    snprintf(name, sizeof name, ".s.set.commit.%ld", dead2);
    join(path, sizeof path, dir, name);
    assert_int_equal(mkdir(path, 0755), 0);
    strcat(path, "/s_0001.txt");
    test_write_file(path, "committed");
    snprintf(name, sizeof name, "s.exr.tmp.%ld", live);
    join(path, sizeof path, dir, name);
    test_write_file(path, "running");
    snprintf(name, sizeof name, "other.exr.tmp.%ld", dead);
    join(path, sizeof path, dir, name);
    test_write_file(path, "not ours");
    notes = 0;
    int found = atomic_clean_stale(stem, count_note);
    /* the commit folder's pid may run again by now: then it is left alone, and said so */
    assert_int_equal(found, 4);
    assert_int_equal(notes, 4);
    assert_int_equal(count_temp_files(dir), 2); /* the running process's and the other output's */
    snprintf(name, sizeof name, "s.exr.tmp.%ld", live);
    join(path, sizeof path, dir, name);
    assert_int_equal(file_size(path), 7);
    snprintf(name, sizeof name, ".s.set.tmp.%ld", dead);
    join(path, sizeof path, dir, name);
    assert_int_equal(file_size(path), -1);
    if (kill((pid_t)(dead2), 0) != 0) {
        join(path, sizeof path, dir, "s_0001.txt");
        assert_int_equal(file_size(path), 9); /* the commit folder's file moved into place */
        snprintf(name, sizeof name, ".s.set.commit.%ld", dead2);
        join(path, sizeof path, dir, name);
        assert_int_equal(file_size(path), -1);
    }
    test_rmtree(dir);
}

/* The manifest "<stem>_frames.csv" (io.h ATOMIC_SET_MANIFEST): a reader who sees it sees the whole set. At
 * every file moved into place (the wrote() callback, called right after each rename) the manifest is absent
 * until the very last, which is the manifest itself — also when its name sorts before other files of the set
 * ("s_viewer.html" after "s_frames.csv"). Broken variant: the files moved in plain name order with the old
 * manifest left in place: the old manifest is seen beside new frames at the first callback. */
static char manifest_path[9000];
static int moves, manifest_seen_early, manifest_last;

static void check_manifest(const char *path)
{
    int last = strstr(path, ATOMIC_SET_MANIFEST) != NULL;
    if (!last && file_size(manifest_path) >= 0) manifest_seen_early++;
    if (last) manifest_last = ++moves;
    else moves++;
}

static void test_atomic_set_manifest_last(void **state)
{
    (void)state;
    char *dir = test_tmpdir(), stem[512], path[9000];
    dp_error err;
    atomic_set set;
    join(stem, sizeof stem, dir, "s");
    join(manifest_path, sizeof manifest_path, dir, "s" ATOMIC_SET_MANIFEST);
    test_write_file(manifest_path, "old set");
    join(path, sizeof path, dir, "s_0000.txt");
    test_write_file(path, "old");
    assert_int_equal(atomic_set_open(&set, stem, &err), 0);
    const char *files[] = {"_0000.txt", "_0001.txt", ATOMIC_SET_MANIFEST, "_viewer.html"};
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s%s", set.stem, files[i]);
        test_write_file(path, "new");
    }
    moves = manifest_seen_early = manifest_last = 0;
    assert_int_equal(atomic_set_commit(&set, check_manifest, &err), 0);
    assert_int_equal(moves, 4);
    assert_int_equal(manifest_seen_early, 0);
    assert_int_equal(manifest_last, 4);
    assert_int_equal(file_size(manifest_path), 3); /* the new manifest */
    test_rmtree(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_atomic_no_temp_left),
        cmocka_unit_test(test_atomic_missing_folder_and_make_parent_dirs),
        cmocka_unit_test(test_atomic_failed_write_keeps_old_file),
        cmocka_unit_test(test_atomic_open_commit_abort),
        cmocka_unit_test(test_atomic_fopen_fclose_fabort),
        cmocka_unit_test(test_frames_csv),
        cmocka_unit_test(test_atomic_set_and_stale),
        cmocka_unit_test(test_atomic_set_manifest_last),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

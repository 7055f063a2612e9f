/* dartspp._dartspp: the CPython extension over the embedding API (include/dartspp/api.h). Written against the
 * C API of CPython and NumPy directly (not cffi): the library is C, Debian's python3-dev and python3-numpy are
 * all it needs, and releasing the GIL, calling back into Python from the render and catching SIGINT are plain
 * C here. The Python-facing functions (render, compare, keys, ...) are in __init__.py; this module converts
 * arguments and results and nothing else. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include <signal.h>
#include <string.h>

#include "dartspp/api.h"

static PyObject *Error, *SceneError; /* the module's exception types, created once at import */

/* Set by the SIGINT handler installed for a render in the main thread (a signal handler can reach nothing
 * else): sigint_stop is the render's stop flag (the API also sets it when progress asks to stop), sigint_seen
 * says that the signal came. */
static dp_stop_flag sigint_stop;
static volatile sig_atomic_t sigint_seen;

static void on_sigint(int sig)
{
    (void)sig;
    sigint_seen = 1;
    sigint_stop = 1;
}

static PyObject *raise_error(const dp_error *err)
{
    PyErr_SetString(err->kind == DP_ERROR_INPUT ? SceneError : Error, err->msg);
    return NULL;
}

/* ---- progress from the render thread ---- */
typedef struct {
    PyObject *callback;     /* may be NULL */
    PyObject *exc_type, *exc_value, *exc_tb; /* an exception the callback raised: the render stops, it is raised */
} progress_ctx;

static int call_progress(void *ctx, long passes, double seconds, double r_vol, double r_surf)
{
    progress_ctx *pc = ctx;
    if (!pc->callback) return 0;
    PyGILState_STATE g = PyGILState_Ensure();
    PyObject *ret = PyObject_CallFunction(pc->callback, "ld(dd)", passes, seconds, r_vol, r_surf);
    int stop = 0;
    if (!ret) {
        PyErr_Fetch(&pc->exc_type, &pc->exc_value, &pc->exc_tb);
        stop = 1;
    } else {
        stop = PyObject_IsTrue(ret) > 0;
        Py_DECREF(ret);
    }
    PyGILState_Release(g);
    return stop;
}

/* ---- results ---- */
static PyObject *float_array(const float *v, int nd, npy_intp *dims)
{
    PyObject *a = PyArray_SimpleNew(nd, dims, NPY_FLOAT32);
    if (a && PyArray_NBYTES((PyArrayObject *)a) > 0) memcpy(PyArray_DATA((PyArrayObject *)a), v, (size_t)PyArray_NBYTES((PyArrayObject *)a));
    return a;
}

static PyObject *double_array(const double *v, int nd, npy_intp *dims)
{
    PyObject *a = PyArray_SimpleNew(nd, dims, NPY_FLOAT64);
    if (a && PyArray_NBYTES((PyArrayObject *)a) > 0)
        memcpy(PyArray_DATA((PyArrayObject *)a), v, (size_t)PyArray_NBYTES((PyArrayObject *)a));
    return a;
}

/* Sets d[key] = value and drops the reference; 0, or -1 (value NULL or the insertion failed). */
static int put(PyObject *d, const char *key, PyObject *value)
{
    if (!value) return -1;
    int rc = PyDict_SetItemString(d, key, value);
    Py_DECREF(value);
    return rc;
}

/* The run's figures (dp_render_result.stats) as a dict, in their order: int for the counts, else float. */
static PyObject *stats_dict(const dp_render_result *r)
{
    PyObject *d = PyDict_New();
    for (int i = 0; d && i < r->stat_count; i++) {
        const dp_stat *st = &r->stats[i];
        if (put(d, st->name, st->integer ? PyLong_FromLong((long)st->value) : PyFloat_FromDouble(st->value)))
            Py_CLEAR(d);
    }
    return d;
}

/* d["derivatives"]: (K, height, width, 3), d["derivative_frames"]: (K, frames, height, width, 3); None when
 * none were asked for (and the frames None without frames). */
static int put_derivs(PyObject *d, const dp_render_result *r)
{
    npy_intp img[4] = {r->deriv_count, r->height, r->width, 3};
    npy_intp frames[5] = {r->deriv_count, r->frame_count, r->height, r->width, 3};
    int have = r->deriv_count > 0 && r->derivs;
    return put(d, "derivatives", have ? float_array(r->derivs, 4, img) : Py_NewRef(Py_None)) ||
           put(d, "derivative_frames", have && r->deriv_frames ? float_array(r->deriv_frames, 5, frames)
                                                                : Py_NewRef(Py_None));
}

/* d["waveforms"]: (channels, azimuth_steps, bins), d["points"]: (N, 8), d["range_bin"]; None for a camera
 * that is not a lidar. */
static int put_lidar(PyObject *d, const dp_render_result *r)
{
    npy_intp wave[3] = {r->lidar_channels, r->lidar_azimuth_steps, r->lidar_bins}, pts[2] = {r->point_count, 8};
    int have = r->waveforms != NULL;
    return put(d, "waveforms", have ? float_array(r->waveforms, 3, wave) : Py_NewRef(Py_None)) ||
           put(d, "points", have ? float_array(r->points, 2, pts) : Py_NewRef(Py_None)) ||
           put(d, "range_bin", have ? PyFloat_FromDouble(r->lidar_range_bin) : Py_NewRef(Py_None));
}

/* d["amcw"]: (F, height, width, 3) complex64, d["amcw_depth"]: (height, width) float32, d["amcw_mhz"]: the F
 * frequencies; None without renderer.amcw_frequencies (docs/amcw.md). */
static int put_amcw(PyObject *d, const dp_render_result *r)
{
    if (r->amcw_count <= 0 || !r->amcw)
        return put(d, "amcw", Py_NewRef(Py_None)) || put(d, "amcw_depth", Py_NewRef(Py_None)) ||
               put(d, "amcw_mhz", Py_NewRef(Py_None));
    npy_intp dims[4] = {r->amcw_count, r->height, r->width, 3}, ddims[2] = {r->height, r->width}, fdims[1] = {r->amcw_count};
    PyObject *a = PyArray_SimpleNew(4, dims, NPY_COMPLEX64);
    if (a) memcpy(PyArray_DATA((PyArrayObject *)a), r->amcw, (size_t)PyArray_NBYTES((PyArrayObject *)a));
    return put(d, "amcw", a) || put(d, "amcw_depth", float_array(r->amcw_depth, 2, ddims)) ||
           put(d, "amcw_mhz", double_array(r->amcw_mhz, 1, fdims));
}

static PyObject *result_dict(const dp_render_result *r)
{
    PyObject *d = PyDict_New();
    if (!d) return NULL;
    npy_intp img[3] = {r->height, r->width, 3}, frames[4] = {r->frame_count, r->height, r->width, 3};
    npy_intp times[2] = {r->frame_count, 2}, log[2] = {r->log_rows, DP_LOG_COLUMNS};
    PyObject *names = PyTuple_New(DP_LOG_COLUMNS);
    for (int i = 0; names && i < DP_LOG_COLUMNS; i++) PyTuple_SET_ITEM(names, i, PyUnicode_FromString(DP_LOG_COLUMN_NAMES[i]));
    int rc = put(d, "log_columns", names) || put(d, "image", float_array(r->image, 3, img)) ||
             put(d, "frames", r->frames ? float_array(r->frames, 4, frames) : Py_NewRef(Py_None)) ||
             put(d, "frame_times", double_array(r->frame_times, 2, times)) ||
             put(d, "plan_json", PyUnicode_FromString(r->plan_json)) ||
             put(d, "integrator", PyUnicode_FromString(r->integrator)) ||
             put(d, "warnings", PyUnicode_FromString(r->warnings ? r->warnings : "")) ||
             put(d, "gated", PyBool_FromLong(r->gated)) || put(d, "camera_warped", PyBool_FromLong(r->camera_warped)) ||
             put(d, "gate_start", PyFloat_FromDouble(r->gate_start)) ||
             put(d, "gate_end", PyFloat_FromDouble(r->gate_end)) || put(d, "passes", PyLong_FromLong(r->passes)) ||
             put(d, "interrupted", PyBool_FromLong(r->interrupted)) ||
             put(d, "seconds", PyFloat_FromDouble(r->seconds)) || put(d, "stats", stats_dict(r)) ||
             put(d, "log", double_array(r->log, 2, log)) || put_derivs(d, r) || put_lidar(d, r) || put_amcw(d, r);
    if (rc) Py_CLEAR(d);
    return d;
}

/* ---- images ---- */
/* An (height, width, 3) float32 view of any array-like; NULL with SceneError naming `what`. */
static PyArrayObject *rgb_array(PyObject *o, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(o, NPY_FLOAT32, 3, 3, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (a && PyArray_DIM(a, 2) == 3 && PyArray_DIM(a, 0) > 0 && PyArray_DIM(a, 1) > 0) return a;
    Py_XDECREF(a);
    PyErr_Clear();
    PyErr_Format(SceneError, "%s: expected an array of shape (height, width, 3)", what);
    return NULL;
}

static image_rgb image_of(PyArrayObject *a)
{
    return (image_rgb){.width = (int)PyArray_DIM(a, 1), .height = (int)PyArray_DIM(a, 0), .rgb = PyArray_DATA(a)};
}

/* ---- render ---- */
typedef struct {
    const char *scene_path, *scene_text, *scene_name, *base_dir, *reference_path;
    PyObject *sets, *reference, *progress, *derivatives;
    unsigned long long seed;
    long spp;
    double time, log_every, max_memory;
    int threads, catch_sigint;
} render_args;

/* The strings of a list of str (None: none): borrowed UTF-8 pointers into the list's items. */
static int utf8_list(PyObject *list, const char ***out, int *n)
{
    *out = NULL;
    *n = 0;
    if (list == Py_None) return 0;
    Py_ssize_t len = PyList_Size(list);
    if (len < 0) return -1;
    *out = PyMem_Calloc((size_t)len + 1, sizeof(char *));
    if (!*out) return PyErr_NoMemory(), -1;
    for (Py_ssize_t i = 0; i < len; i++)
        if (!((*out)[i] = PyUnicode_AsUTF8(PyList_GET_ITEM(list, i)))) return -1;
    *n = (int)len;
    return 0;
}

static PyObject *py_render(PyObject *self, PyObject *args, PyObject *kw)
{
    (void)self;
    static char *names[] = {"scene_path", "scene_text", "scene_name", "base_dir", "sets", "seed", "spp", "time",
                            "threads", "max_memory", "reference_path", "reference", "log_every", "progress",
                            "catch_sigint", "derivatives", NULL};
    render_args a = {.sets = Py_None, .reference = Py_None, .progress = Py_None, .derivatives = Py_None};
    if (!PyArg_ParseTupleAndKeywords(args, kw, "zzzzOKldidzOdOpO", names, &a.scene_path, &a.scene_text,
                                     &a.scene_name, &a.base_dir, &a.sets, &a.seed, &a.spp, &a.time, &a.threads,
                                     &a.max_memory, &a.reference_path, &a.reference, &a.log_every, &a.progress,
                                     &a.catch_sigint, &a.derivatives))
        return NULL;
    const char **sets, **derivs = NULL;
    int set_count, deriv_count = 0;
    PyArrayObject *ref = NULL;
    if (utf8_list(a.sets, &sets, &set_count) || utf8_list(a.derivatives, &derivs, &deriv_count) ||
        (a.reference != Py_None && !(ref = rgb_array(a.reference, "reference")))) {
        PyMem_Free(sets);
        PyMem_Free(derivs);
        return NULL;
    }
    progress_ctx pc = {.callback = a.progress != Py_None ? a.progress : NULL};
    dp_stop_flag own_stop = 0;
    dp_render_request rq = {
        .scene_path = a.scene_path, .scene_text = a.scene_text, .scene_name = a.scene_name, .base_dir = a.base_dir,
        .sets = sets, .set_count = set_count, .seed = a.seed, .spp = a.spp, .time_limit = a.time,
        .threads = a.threads, .max_memory = a.max_memory, .reference_path = a.reference_path,
        .reference_rgb = ref ? PyArray_DATA(ref) : NULL, .ref_width = ref ? (int)PyArray_DIM(ref, 1) : 0,
        .ref_height = ref ? (int)PyArray_DIM(ref, 0) : 0, .log_every = a.log_every, .progress = call_progress,
        .progress_ctx = &pc, .stop = a.catch_sigint ? &sigint_stop : &own_stop, .derivatives = derivs,
        .derivative_count = deriv_count};
    struct sigaction ours = {.sa_handler = on_sigint}, before;
    sigemptyset(&ours.sa_mask);
    if (a.catch_sigint) {
        sigint_seen = 0;
        sigint_stop = 0;
        sigaction(SIGINT, &ours, &before);
    }
    dp_render_result res;
    dp_error err;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = dp_render(&rq, &res, &err);
    Py_END_ALLOW_THREADS
    int interrupted = a.catch_sigint && sigint_seen;
    if (a.catch_sigint) sigaction(SIGINT, &before, NULL);
    Py_XDECREF(ref);
    PyMem_Free(sets);
    PyMem_Free(derivs);
    PyObject *out = NULL;
    if (pc.exc_type) PyErr_Restore(pc.exc_type, pc.exc_value, pc.exc_tb);
    else if (rc) raise_error(&err);
    else if ((out = result_dict(&res)) && put(out, "sigint", PyBool_FromLong(interrupted))) Py_CLEAR(out);
    dp_render_result_free(&res);
    return out;
}

/* check_option(name, text): dp_option_parse; an int for whole-number options, else a float. */
static PyObject *py_check_option(PyObject *self, PyObject *args)
{
    (void)self;
    const char *name, *text;
    if (!PyArg_ParseTuple(args, "ss", &name, &text)) return NULL;
    double v = 0;
    uint64_t u = 0;
    int whole = 0;
    dp_error err;
    if (dp_option_parse(name, text, &v, &u, &whole, &err)) return raise_error(&err);
    return whole ? PyLong_FromUnsignedLongLong(u) : PyFloat_FromDouble(v);
}

static PyObject *py_compare(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ao, *bo;
    if (!PyArg_ParseTuple(args, "OO", &ao, &bo)) return NULL;
    PyArrayObject *a = rgb_array(ao, "image"), *b = a ? rgb_array(bo, "reference") : NULL;
    PyObject *out = NULL;
    if (b) {
        image_rgb ia = image_of(a), ib = image_of(b);
        image_error e;
        dp_error err;
        if (dp_compare(&ia, &ib, &e, &err)) raise_error(&err);
        else
            out = Py_BuildValue("{s:d,s:d,s:d,s:d,s:d,s:l,s:l}", "mse", e.mse, "rmse", e.rmse, "rel_mse", e.rel_mse,
                                "mse_q99", e.mse_q99, "q99", e.q99, "nonfinite", e.nonfinite, "pixels", e.pixels);
    }
    Py_XDECREF(a);
    Py_XDECREF(b);
    return out;
}

static PyObject *py_read_image(PyObject *self, PyObject *args)
{
    (void)self;
    const char *path;
    if (!PyArg_ParseTuple(args, "s", &path)) return NULL;
    image_rgb img = {0};
    dp_error err;
    if (image_read(path, &img, &err)) return raise_error(&err);
    npy_intp dims[3] = {img.height, img.width, 3};
    PyObject *a = float_array(img.rgb, 3, dims);
    image_free(&img);
    return a;
}

/* write_image(path, array, frame, gated, camera_warped, gate_start, gate_end, frame_times, integrator, plan,
 * passes) */
static PyObject *py_write_image(PyObject *self, PyObject *args)
{
    (void)self;
    const char *path, *integrator, *plan;
    PyObject *ao, *times;
    int frame, gated, warped;
    long passes;
    double start, end;
    if (!PyArg_ParseTuple(args, "sOippddOzzl", &path, &ao, &frame, &gated, &warped, &start, &end, &times, &integrator,
                          &plan, &passes))
        return NULL;
    PyArrayObject *a = rgb_array(ao, path);
    PyArrayObject *t = a ? (PyArrayObject *)PyArray_FROMANY(times, NPY_FLOAT64, 2, 2, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST) : NULL;
    PyObject *out = NULL;
    if (t) {
        dp_render_result r = {.gated = gated, .camera_warped = warped, .gate_start = start, .gate_end = end,
                              .frame_count = (int)PyArray_DIM(t, 0), .frame_times = PyArray_DATA(t),
                              .integrator = (char *)integrator, .plan_json = (char *)plan, .passes = passes};
        image_rgb img = image_of(a);
        dp_error err;
        int rc;
        Py_BEGIN_ALLOW_THREADS
        rc = dp_write_image(path, &img, &r, frame, &err);
        Py_END_ALLOW_THREADS
        out = rc ? raise_error(&err) : Py_NewRef(Py_None);
    }
    Py_XDECREF(a);
    Py_XDECREF(t);
    return out;
}

static PyObject *py_keys(PyObject *self, PyObject *noargs)
{
    (void)self;
    (void)noargs;
    int n = dp_key_count();
    PyObject *list = PyList_New(n);
    for (int i = 0; list && i < n; i++) {
        dp_key_row k;
        dp_key_get(i, &k);
        PyObject *row = Py_BuildValue("{s:s,s:s,s:s,s:s,s:s,s:s,s:O,s:s}", "section", k.section, "name", k.name, "type",
                                      k.type, "default", k.def, "range", k.range, "read_by", k.readers,
                                      "changes_image", k.changes_image ? Py_True : Py_False, "meaning", k.meaning);
        if (!row) Py_CLEAR(list);
        else PyList_SET_ITEM(list, i, row);
    }
    return list;
}

static PyMethodDef methods[] = {
    {"render", (PyCFunction)(void (*)(void))py_render, METH_VARARGS | METH_KEYWORDS, "dp_render (see __init__.render)"},
    {"check_option", py_check_option, METH_VARARGS, "dp_option_parse: an option's text parsed and range-checked"},
    {"compare", py_compare, METH_VARARGS, "dp_compare (see __init__.compare)"},
    {"read_image", py_read_image, METH_VARARGS, "an EXR or PFM image as a (height, width, 3) float32 array"},
    {"write_image", py_write_image, METH_VARARGS, "dp_write_image (see Result.write_exr)"},
    {"keys", py_keys, METH_NOARGS, "the key table, one dict per key"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_dartspp", "the C side of the dartspp package", -1, methods,
                                    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__dartspp(void)
{
    import_array();
    PyObject *m = PyModule_Create(&module);
    if (!m) return NULL;
    Error = PyErr_NewExceptionWithDoc("dartspp.Error", "A render failed.", PyExc_RuntimeError, NULL);
    PyObject *bases = Error ? PyTuple_Pack(2, Error, PyExc_ValueError) : NULL;
    SceneError = bases ? PyErr_NewExceptionWithDoc("dartspp.SceneError",
                                                   "Bad input: the scene, a key, an option or a file it names; "
                                                   "refused before any work.", bases, NULL)
                       : NULL;
    Py_XDECREF(bases);
    if (!SceneError || PyModule_AddObjectRef(m, "Error", Error) || PyModule_AddObjectRef(m, "SceneError", SceneError)) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

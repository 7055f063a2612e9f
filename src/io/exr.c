/* OpenEXR images through the library's C API (OpenEXRCore): float32 RGB scanline files with ZIP
 * compression and dartspp metadata out; R,G,B or Y of any pixel type in.
 *
 * Both directions use our own file descriptor behind the library's custom stream hooks: writing goes
 * to the atomic temp file (then fsync + rename), and reading gets messages with errno text and a
 * size query that lets the library check chunk offsets against the real file size. */
#include "dartspp/io.h"

#include <errno.h>
#include <fcntl.h>
#include <openexr.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define EXR_OK EXR_ERR_SUCCESS

/* The user data of a context: our file and the first message the library or the stream reported. */
typedef struct {
    int fd;
    char msg[512];
} exr_stream;

static void note(exr_stream *s, const char *msg)
{
    if (!s->msg[0]) snprintf(s->msg, sizeof s->msg, "%s", msg);
}

/* Read contexts take no lock in exr_get_user_data, so the handler may call it. */
static void on_read_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    (void)code;
    if (exr_get_user_data(ctxt, &ud) == EXR_OK && ud) note(ud, msg);
}

/* Write contexts may report while holding their lock, so nothing here calls back into the library;
 * stream failures are recorded by stream_write itself and API failures map to their result code. */
static void on_write_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg;
}

static int64_t stream_read(exr_const_context_t ctxt, void *ud, void *buf, uint64_t sz, uint64_t off,
                           exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    uint64_t done = 0;
    while (done < sz) {
        if (off + done > (uint64_t)INT64_MAX) break;
        ssize_t n = pread(s->fd, (char *)buf + done, sz - done, (off_t)(off + done));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            error_cb(ctxt, EXR_ERR_READ_IO, "read failed: %s", strerror(errno));
            return -1;
        }
        if (n == 0) break;
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t stream_size(exr_const_context_t ctxt, void *ud)
{
    struct stat st;
    (void)ctxt;
    return fstat(((exr_stream *)ud)->fd, &st) == 0 ? (int64_t)st.st_size : -1;
}

static int64_t stream_write(exr_const_context_t ctxt, void *ud, const void *buf, uint64_t sz,
                            uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    exr_stream *s = ud;
    uint64_t done = 0;
    (void)ctxt;
    (void)error_cb;
    while (done < sz) {
        ssize_t n = pwrite(s->fd, (const char *)buf + done, sz - done, (off_t)(off + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            char m[256];
            int e = n < 0 ? errno : 0;
            snprintf(m, sizeof m, "write failed: %s%s", e ? strerror(e) : "no space written", io_errno_hint(e));
            note(s, m);
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int fail_exr(dp_error *err, dp_error_kind kind, const char *path, const exr_stream *s, exr_result_t rv)
{
    return dp_fail_kind(err, kind, "%s: %s", path, s->msg[0] ? s->msg : exr_get_default_error_message(rv));
}

/* Offset of a channel in an interleaved RGB pixel; -1 for channels we do not handle. */
static int rgb_offset(const char *name)
{
    if (!strcmp(name, "R")) return 0;
    if (!strcmp(name, "G")) return 1;
    if (!strcmp(name, "B")) return 2;
    return -1;
}

/* Points one coding channel at rows of an interleaved float RGB image, converting to/from float. */
static void bind_channel(exr_coding_channel_info_t *ch, float *rgb, int width, size_t row, int offset)
{
    ch->user_bytes_per_element = 4;
    ch->user_data_type = EXR_PIXEL_FLOAT;
    ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
    ch->user_line_stride = 3 * (int32_t)sizeof(float) * width;
    ch->decode_to_ptr = (uint8_t *)(rgb + row * (size_t)width * 3 + (size_t)offset);
}

/* ---- writing ---- */

static exr_result_t write_meta(exr_context_t ctx, int part, const image_meta *m)
{
    exr_result_t rv = EXR_OK;
    if (m->time_unit) rv = exr_attr_set_string(ctx, part, "dartspp.timeUnit", m->time_unit);
    if (rv == EXR_OK && m->gated) rv = exr_attr_set_double(ctx, part, "dartspp.gateStart", m->gate_start);
    if (rv == EXR_OK && m->gated) rv = exr_attr_set_double(ctx, part, "dartspp.gateEnd", m->gate_end);
    if (rv == EXR_OK) rv = exr_attr_set_int(ctx, part, "dartspp.cameraWarped", m->camera_warped);
    if (rv == EXR_OK) rv = exr_attr_set_int(ctx, part, "dartspp.frame", m->frame_index);
    if (rv == EXR_OK && m->integrator)
        rv = exr_attr_set_string(ctx, part, "dartspp.integrator", m->integrator);
    if (rv == EXR_OK && m->plan) rv = exr_attr_set_string(ctx, part, "dartspp.plan", m->plan);
    if (rv == EXR_OK && m->passes > 0)
        rv = exr_attr_set_int(ctx, part, "dartspp.passes", m->passes > INT32_MAX ? INT32_MAX : (int32_t)m->passes);
    return rv;
}

static exr_result_t define_header(exr_context_t ctx, const image_rgb *img, const image_meta *meta)
{
    static const char *const names[3] = {"R", "G", "B"};
    int part = 0;
    exr_result_t rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_OK)
        rv = exr_initialize_required_attr_simple(ctx, part, img->width, img->height, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < 3 && rv == EXR_OK; ++c)
        rv = exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_OK && meta) rv = write_meta(ctx, part, meta);
    if (rv == EXR_OK) rv = exr_write_header(ctx);
    return rv;
}

/* OpenEXRCore up to 3.4.7 (Debian 12 ships 3.1.5) stores the zlib bytes of a chunk whose compressed size
 * equals its packed size, which readers take for uncompressed data: the chunk reads back as garbage (NaN,
 * 1e38; openexr issue #2306, one chunk in a few hundred of noisy float data). The library's own rule is that
 * a chunk stored at its packed size holds the packed bytes, so after the library's compressor runs, such a
 * chunk gets them. */
typedef struct {
    exr_result_t (*compress)(exr_encode_pipeline_t *enc);
} zip_guard;

static exr_result_t compress_guarded(exr_encode_pipeline_t *enc)
{
    const zip_guard *g = enc->encoding_user_data;
    exr_result_t rv = g->compress(enc);
    if (rv == EXR_OK && enc->compressed_buffer && enc->compressed_buffer != enc->packed_buffer &&
        enc->compressed_bytes == enc->packed_bytes)
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    return rv;
}

static exr_result_t encode_chunk(exr_context_t ctx, const image_rgb *img, int y, exr_encode_pipeline_t *enc,
                                 zip_guard *guard, int *started)
{
    exr_chunk_info_t ci;
    exr_result_t rv = exr_write_scanline_chunk_info(ctx, 0, y, &ci);
    if (rv != EXR_OK) return rv;
    rv = *started ? exr_encoding_update(ctx, 0, &ci, enc) : exr_encoding_initialize(ctx, 0, &ci, enc);
    if (rv != EXR_OK) return rv;
    for (int c = 0; c < enc->channel_count; ++c)
        bind_channel(enc->channels + c, img->rgb, img->width, (size_t)ci.start_y,
                     rgb_offset(enc->channels[c].channel_name));
    if (!*started) {
        rv = exr_encoding_choose_default_routines(ctx, 0, enc);
        if (rv == EXR_OK && enc->compress_fn) {
            guard->compress = enc->compress_fn;
            enc->compress_fn = compress_guarded;
            enc->encoding_user_data = guard;
        }
    }
    *started = 1;
    return rv == EXR_OK ? exr_encoding_run(ctx, 0, enc) : rv;
}

static exr_result_t write_pixels(exr_context_t ctx, const image_rgb *img)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rv == EXR_OK && lines <= 0) rv = EXR_ERR_INVALID_ARGUMENT;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    zip_guard guard = {NULL};
    int started = 0;
    for (int y = 0; rv == EXR_OK && y < img->height; y += lines)
        rv = encode_chunk(ctx, img, y, &enc, &guard, &started);
    if (started) exr_encoding_destroy(ctx, &enc);
    return rv;
}

int exr_write(const char *path, const image_rgb *img, const image_meta *meta, dp_error *err)
{
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0)
        return dp_fail_kind(err, DP_ERROR_INTERNAL, "%s: cannot write an empty image", path);
    char tmp[4096];
    exr_stream s = {.fd = atomic_open(path, tmp, sizeof tmp, err)};
    if (s.fd < 0) return -1;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_write_error;
    init.user_data = &s;
    init.write_fn = stream_write;
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_OK) rv = define_header(ctx, img, meta);
    if (rv == EXR_OK) rv = write_pixels(ctx, img);
    if (ctx) {
        exr_result_t fin = exr_finish(&ctx); /* writes the chunk offset table */
        if (rv == EXR_OK) rv = fin;
    }
    if (rv != EXR_OK) {
        atomic_abort(s.fd, tmp);
        return fail_exr(err, DP_ERROR_OUTPUT, path, &s, rv);
    }
    return atomic_commit(s.fd, tmp, path, err);
}

/* ---- reading ---- */

typedef struct {
    int width, height, min_y, max_y;
    int grey; /* 1: only a Y channel, copied to R, G and B */
} exr_layout;

/* RGB if any of R, G, B is there, else Y; the channels used must not be subsampled. */
static int choose_channels(const exr_attr_chlist_t *cl, exr_layout *lay, const char *path, dp_error *err)
{
    int rgb = 0, y = 0;
    for (int i = 0; i < cl->num_channels; ++i) {
        const exr_attr_chlist_entry_t *e = cl->entries + i;
        int is_rgb = rgb_offset(e->name.str) >= 0, is_y = !strcmp(e->name.str, "Y");
        if ((is_rgb || is_y) && (e->x_sampling != 1 || e->y_sampling != 1))
            return dp_fail(err, "%s: subsampled channel %s is not supported", path, e->name.str);
        rgb |= is_rgb;
        y |= is_y;
    }
    if (!rgb && !y) return dp_fail(err, "%s: no R, G, B or Y channel", path);
    lay->grey = !rgb;
    return 0;
}

static int read_layout(exr_context_t ctx, exr_stream *s, const char *path, exr_layout *lay, dp_error *err)
{
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv = exr_get_storage(ctx, 0, &storage);
    if (rv == EXR_OK && storage != EXR_STORAGE_SCANLINE)
        return dp_fail(err, "%s: only flat scanline EXR images are supported (this one is tiled or deep)",
                       path);
    if (rv == EXR_OK) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv == EXR_OK) rv = exr_get_channels(ctx, 0, &cl);
    if (rv != EXR_OK || !cl) return fail_exr(err, DP_ERROR_INPUT, path, s, rv != EXR_OK ? rv : EXR_ERR_MISSING_REQ_ATTR);
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w <= 0 || h <= 0 || w > INT32_MAX || h > INT32_MAX)
        return dp_fail(err, "%s: invalid data window", path);
    lay->width = (int)w;
    lay->height = (int)h;
    lay->min_y = dw.min.y;
    lay->max_y = dw.max.y;
    return choose_channels(cl, lay, path, err);
}

static void bind_decode(exr_decode_pipeline_t *dec, image_rgb *img, const exr_layout *lay, int start_y)
{
    for (int c = 0; c < dec->channel_count; ++c) {
        exr_coding_channel_info_t *ch = dec->channels + c;
        int off = lay->grey ? (strcmp(ch->channel_name, "Y") ? -1 : 0) : rgb_offset(ch->channel_name);
        if (off < 0 || ch->height == 0) ch->decode_to_ptr = NULL;
        else bind_channel(ch, img->rgb, img->width, (size_t)(start_y - lay->min_y), off);
    }
}

static exr_result_t decode_chunk(exr_context_t ctx, int y, image_rgb *img, const exr_layout *lay,
                                 exr_decode_pipeline_t *dec, int *started)
{
    exr_chunk_info_t ci;
    exr_result_t rv = exr_read_scanline_chunk_info(ctx, 0, y, &ci);
    if (rv != EXR_OK) return rv;
    if (ci.start_y < lay->min_y || (int64_t)ci.start_y + ci.height - 1 > lay->max_y || ci.width != lay->width)
        return EXR_ERR_CORRUPT_CHUNK;
    rv = *started ? exr_decoding_update(ctx, 0, &ci, dec) : exr_decoding_initialize(ctx, 0, &ci, dec);
    if (rv != EXR_OK) return rv;
    bind_decode(dec, img, lay, ci.start_y);
    if (!*started) rv = exr_decoding_choose_default_routines(ctx, 0, dec);
    *started = 1;
    return rv == EXR_OK ? exr_decoding_run(ctx, 0, dec) : rv;
}

static exr_result_t decode_pixels(exr_context_t ctx, image_rgb *img, const exr_layout *lay)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, 0, &lines);
    if (rv == EXR_OK && lines <= 0) rv = EXR_ERR_CORRUPT_CHUNK;
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int started = 0;
    for (int64_t y = lay->min_y; rv == EXR_OK && y <= lay->max_y; y += lines)
        rv = decode_chunk(ctx, (int)y, img, lay, &dec, &started);
    if (started) exr_decoding_destroy(ctx, &dec);
    return rv;
}

static void grey_to_rgb(image_rgb *img)
{
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; ++i) img->rgb[3 * i + 1] = img->rgb[3 * i + 2] = img->rgb[3 * i];
}

static int read_image(exr_context_t ctx, exr_stream *s, const char *path, image_rgb *img, dp_error *err)
{
    exr_layout lay = {0, 0, 0, 0, 0};
    if (read_layout(ctx, s, path, &lay, err) != 0) return -1;
    if (image_alloc(img, lay.width, lay.height, err) != 0) {
        char why[sizeof err->msg];
        snprintf(why, sizeof why, "%s", err ? err->msg : "");
        return dp_fail_kind(err, err ? err->kind : DP_ERROR_INPUT, "%s: %s", path, why);
    }
    exr_result_t rv = decode_pixels(ctx, img, &lay);
    if (rv != EXR_OK) return fail_exr(err, DP_ERROR_INPUT, path, s, rv);
    if (lay.grey) grey_to_rgb(img);
    return 0;
}

/* Opens path for reading through our stream (errors reported with its path): 0 with *ctx (when the header
 * parsed; exr_finish and close(s->fd) after), or -1 with err and nothing left open. */
static int exr_open_read(const char *path, exr_stream *s, exr_context_t *ctx, dp_error *err)
{
    struct stat st;
    *ctx = NULL;
    s->fd = open(path, O_RDONLY | O_CLOEXEC);
    if (s->fd < 0) return dp_fail(err, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(s->fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(s->fd);
        return dp_fail(err, "%s: not a regular file", path);
    }
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_read_error;
    init.user_data = s;
    init.read_fn = stream_read;
    init.size_fn = stream_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_result_t rv = exr_start_read(ctx, path, &init);
    if (rv == EXR_OK) return 0;
    /* OpenEXR's own words for a file of another kind ("Unable to read magic and version flags") name no cause */
    int rc = rv == EXR_ERR_FILE_BAD_HEADER || rv == EXR_ERR_READ_IO
                 ? dp_fail_kind(err, DP_ERROR_INPUT, "%s: not an OpenEXR image (%s)", path,
                                s->msg[0] ? s->msg : exr_get_default_error_message(rv))
                 : fail_exr(err, DP_ERROR_INPUT, path, s, rv);
    if (*ctx) exr_finish(ctx);
    close(s->fd);
    return rc;
}

int exr_read(const char *path, image_rgb *img, dp_error *err)
{
    img->width = img->height = 0;
    img->rgb = NULL;
    exr_stream s = {0};
    exr_context_t ctx;
    if (exr_open_read(path, &s, &ctx, err)) return -1;
    int rc = read_image(ctx, &s, path, img, err);
    exr_finish(&ctx);
    close(s.fd);
    if (rc != 0) image_free(img);
    return rc;
}

int exr_read_int_attribute(const char *path, const char *name, int *value, dp_error *err)
{
    exr_stream s = {0};
    exr_context_t ctx;
    if (exr_open_read(path, &s, &ctx, err)) return -1;
    int32_t v = 0;
    exr_result_t rv = exr_attr_get_int(ctx, 0, name, &v);
    int rc = rv == EXR_OK ? 0 : dp_fail(err, "%s: no int attribute %s (OpenEXR: %s)", path, name, exr_get_default_error_message(rv));
    exr_finish(&ctx);
    close(s.fd);
    if (!rc) *value = v;
    return rc;
}

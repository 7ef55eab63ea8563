/* heliodon — OpenEXR images through the OpenEXRCore C API (see exr.h). */
#include "heliodon/exr.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <openexr.h>

#include "heliodon/header.h"
#include "heliodon/io.h"

const float hd_exr_chroma_radiance[8] = {
    0.640f, 0.330f, 0.290f, 0.600f, 0.150f, 0.060f, 1.0f / 3.0f, 1.0f / 3.0f
};
const float hd_exr_chroma_xyz[8] = {
    1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 1.0f / 3.0f, 1.0f / 3.0f
};

/* Attributes that OpenEXR manages itself: never set as string attributes. */
static const char *const reserved_attrs[] = {
    "channels", "compression", "dataWindow", "displayWindow", "lineOrder",
    "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth", "tiles",
    "type", "name", "version", "chunkCount", "chromaticities", NULL
};

/* ---- OpenEXRCore error capture ----
 * The library reports details through a callback; keep the last message
 * (cleared before each call, see EXR_CALL). */
static _Thread_local char exr_msg[512];
#define EXR_CALL(call) (exr_msg[0] = 0, (call))

static void exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    snprintf(exr_msg, sizeof exr_msg, "%s", msg && *msg ? msg : exr_get_default_error_message(code));
}

/* Format the failure of an OpenEXRCore call. */
static hd_status exr_failure(hd_status st, const char *name, const char *what, exr_result_t rv)
{
    if (exr_msg[0])
        return hd_fail(st, "%s: %s: %s (%s)", name, what, exr_msg, exr_get_error_code_as_string(rv));
    return hd_fail(st, "%s: %s: %s (%s)", name, what, exr_get_default_error_message(rv),
                   exr_get_error_code_as_string(rv));
}

static void init_context(exr_context_initializer_t *init)
{
    exr_context_initializer_t def = EXR_DEFAULT_CONTEXT_INITIALIZER;
    *init = def;
    init->error_handler_fn = exr_error_cb;
    init->max_image_width = HD_EXR_MAXSIDE;
    init->max_image_height = HD_EXR_MAXSIDE;
    init->max_tile_width = 65536;
    init->max_tile_height = 65536;
}

/* ---- image container ---- */

void hd_exr_init(hd_exr_image *img)
{
    memset(img, 0, sizeof *img);
    img->compression = HD_EXR_ZIP;
}

void hd_exr_free(hd_exr_image *img)
{
    for (int i = 0; i < img->nchan; i++) {
        free(img->chan[i].name);
        free(img->chan[i].data);
    }
    free(img->chan);
    for (int i = 0; i < img->nattr; i++) {
        free(img->attr[i].name);
        free(img->attr[i].value);
    }
    free(img->attr);
    hd_exr_init(img);
}

hd_status hd_exr_set_size(hd_exr_image *img, int xres, int yres)
{
    if (img->nchan > 0 && (xres != img->xres || yres != img->yres))
        return hd_fail(HD_ERR_RANGE, "EXR image: cannot change the size (%dx%d) once channels exist",
                       img->xres, img->yres);
    if (xres < 1 || yres < 1 || xres > HD_EXR_MAXSIDE || yres > HD_EXR_MAXSIDE)
        return hd_fail(HD_ERR_RANGE, "EXR image: size %dx%d out of range (1..%d per side)",
                       xres, yres, HD_EXR_MAXSIDE);
    img->xres = xres;
    img->yres = yres;
    return HD_OK;
}

int hd_exr_find_channel(const hd_exr_image *img, const char *name)
{
    for (int i = 0; i < img->nchan; i++)
        if (!strcmp(img->chan[i].name, name))
            return i;
    return -1;
}

/* Add a channel with given data (taken over) or zeroed data if NULL. */
static hd_status add_channel_data(hd_exr_image *img, const char *name, hd_exr_pixtype type,
                                  float *data, int *index)
{
    size_t len = strlen(name);
    if (len < 1 || len > 255)
        return hd_fail(HD_ERR_RANGE, "EXR channel name '%s': must be 1 to 255 bytes long", name);
    if (type != HD_EXR_HALF && type != HD_EXR_FLOAT && type != HD_EXR_UINT)
        return hd_fail(HD_ERR_RANGE, "EXR channel %s: bad pixel type %d", name, (int)type);
    if (hd_exr_find_channel(img, name) >= 0)
        return hd_fail(HD_ERR_USAGE, "EXR channel %s: defined twice", name);
    if (img->xres < 1 || img->yres < 1)
        return hd_fail(HD_ERR_USAGE, "EXR channel %s: image size not set", name);
    if (img->nchan >= 4096)
        return hd_fail(HD_ERR_RANGE, "EXR image: more than 4096 channels");
    hd_exr_channel *nc = hd_realloc_array(img->chan, (size_t)img->nchan + 1, sizeof *nc);
    if (!nc)
        return HD_ERR_NOMEM;
    img->chan = nc;
    char *nm = hd_strdup(name);
    if (!nm)
        return HD_ERR_NOMEM;
    if (!data) {
        data = hd_calloc((size_t)img->xres * (size_t)img->yres, sizeof(float));
        if (!data) {
            free(nm);
            return hd_fail_context(HD_ERR_NOMEM, "EXR channel %s", name);
        }
    }
    nc[img->nchan].name = nm;
    nc[img->nchan].type = type;
    nc[img->nchan].data = data;
    if (index)
        *index = img->nchan;
    img->nchan++;
    return HD_OK;
}

hd_status hd_exr_add_channel(hd_exr_image *img, const char *name, hd_exr_pixtype type, int *index)
{
    return add_channel_data(img, name, type, NULL, index);
}

hd_status hd_exr_set_attr(hd_exr_image *img, const char *name, const char *value)
{
    size_t len = strlen(name);
    if (len < 1 || len > 255)
        return hd_fail(HD_ERR_RANGE, "EXR attribute name '%s': must be 1 to 255 bytes long", name);
    for (int i = 0; reserved_attrs[i]; i++)
        if (!strcmp(name, reserved_attrs[i]))
            return hd_fail(HD_ERR_USAGE, "EXR attribute %s: reserved by OpenEXR", name);
    if (strlen(value) > (size_t)INT32_MAX / 2)
        return hd_fail(HD_ERR_RANGE, "EXR attribute %s: value too long", name);
    char *v = hd_strdup(value);
    if (!v)
        return HD_ERR_NOMEM;
    for (int i = 0; i < img->nattr; i++)
        if (!strcmp(img->attr[i].name, name)) {
            free(img->attr[i].value);
            img->attr[i].value = v;
            return HD_OK;
        }
    hd_exr_attr *na = hd_realloc_array(img->attr, (size_t)img->nattr + 1, sizeof *na);
    char *n = na ? hd_strdup(name) : NULL;
    if (!na || !n) {
        if (na)
            img->attr = na;
        free(v);
        return HD_ERR_NOMEM;
    }
    img->attr = na;
    na[img->nattr].name = n;
    na[img->nattr].value = v;
    img->nattr++;
    return HD_OK;
}

const char *hd_exr_get_attr(const hd_exr_image *img, const char *name)
{
    for (int i = 0; i < img->nattr; i++)
        if (!strcmp(img->attr[i].name, name))
            return img->attr[i].value;
    return NULL;
}

static const char *const comp_names[] = {
    "none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"
};

int hd_exr_parse_compression(const char *word, hd_exr_compression *out)
{
    for (int i = 0; i <= HD_EXR_PIZ; i++)
        if (!strcasecmp(word, comp_names[i])) {
            *out = (hd_exr_compression)i;
            return 0;
        }
    return 1;
}

const char *hd_exr_compression_name(hd_exr_compression c)
{
    return (int)c >= 0 && (int)c <= HD_EXR_DWAB ? comp_names[c] : "unknown";
}

const char *hd_exr_pixtype_name(hd_exr_pixtype t)
{
    switch (t) {
    case HD_EXR_UINT: return "uint";
    case HD_EXR_HALF: return "half";
    case HD_EXR_FLOAT: return "float";
    }
    return "unknown";
}

int hd_exr_is_magic(const uint8_t b[4])
{
    return b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01;
}

/* ---- writing ---- */

typedef struct membuf {
    uint8_t *p;
    size_t len, cap;
    int failed;
} membuf;

static int64_t mem_write(exr_const_context_t ctxt, void *ud, const void *buf, uint64_t sz,
                         uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    membuf *m = ud;
    if (m->failed)
        return -1;
    if (off > SIZE_MAX - sz) {
        m->failed = 1;
        return error_cb(ctxt, EXR_ERR_WRITE_IO, "write offset overflow"), -1;
    }
    size_t end = (size_t)(off + sz);
    if (end > m->cap) {
        size_t ncap = m->cap ? m->cap : 65536;
        while (ncap < end)
            ncap = ncap > SIZE_MAX / 2 ? end : ncap * 2;
        uint8_t *np = hd_realloc_array(m->p, ncap, 1);
        if (!np) {
            m->failed = 1;
            error_cb(ctxt, EXR_ERR_OUT_OF_MEMORY, "%s", hd_errmsg());
            return -1;
        }
        m->p = np;
        m->cap = ncap;
    }
    if (off > m->len) /* gap (not expected): keep it zeroed */
        memset(m->p + m->len, 0, (size_t)off - m->len);
    memcpy(m->p + off, buf, (size_t)sz);
    if (end > m->len)
        m->len = end;
    return (int64_t)sz;
}

/* Prepare a uint32 copy of a channel (values rounded, clamped to the range). */
static uint32_t *to_uint(const hd_exr_image *img, const float *src)
{
    size_t n = (size_t)img->xres * (size_t)img->yres;
    uint32_t *u = hd_malloc_array(n, sizeof *u);
    if (!u)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        float v = src[i];
        if (!(v > 0.0f))
            u[i] = 0;   /* negative and NaN */
        else if (v >= 4294967295.0f)
            u[i] = UINT32_MAX;
        else
            u[i] = (uint32_t)lrint(v);
    }
    return u;
}

hd_status hd_exr_encode(const hd_exr_image *img, hd_exr_compression comp, const char *name,
                        uint8_t **data, size_t *len)
{
    if (!name)
        name = "EXR output";
    *data = NULL;
    *len = 0;
    if (img->xres < 1 || img->yres < 1 || img->xres > HD_EXR_MAXSIDE || img->yres > HD_EXR_MAXSIDE)
        return hd_fail(HD_ERR_RANGE, "%s: image size %dx%d out of range (1..%d per side)",
                       name, img->xres, img->yres, HD_EXR_MAXSIDE);
    if (img->nchan < 1)
        return hd_fail(HD_ERR_USAGE, "%s: image has no channels", name);
    if ((int)comp < 0 || comp > HD_EXR_PIZ)
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: cannot write %s compression (only none, rle, zips, zip, piz)",
                       name, hd_exr_compression_name(comp));

    hd_status st = HD_OK;
    membuf mb = {0};
    exr_context_t ctx = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int enc_init = 0;
    int *map = NULL;            /* pipeline channel -> image channel */
    uint32_t **ubuf = NULL;     /* uint copies, per image channel */
    exr_result_t rv;
    int part = 0;
    exr_context_initializer_t init;
    init_context(&init);
    init.user_data = &mb;
    init.write_fn = mem_write;

#define EXR_TRY(call, what) do { rv = EXR_CALL(call); \
        if (rv != EXR_ERR_SUCCESS) { st = exr_failure(HD_ERR_IO, name, what, rv); goto done; } } while (0)

    EXR_TRY(exr_start_write(&ctx, name, EXR_WRITE_FILE_DIRECTLY, &init), "cannot start writing");
    /* names over 31 bytes need the long-name flag (set only then, so that
     * other files stay readable by old OpenEXR versions) */
    int longnames = 0;
    for (int i = 0; i < img->nchan; i++)
        longnames |= strlen(img->chan[i].name) > 31;
    for (int i = 0; i < img->nattr; i++)
        longnames |= strlen(img->attr[i].name) > 31;
    if (longnames)
        EXR_TRY(exr_set_longname_support(ctx, 1), "cannot enable long names");
    EXR_TRY(exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part), "cannot add image part");
    EXR_TRY(exr_initialize_required_attr_simple(ctx, part, img->xres, img->yres, (exr_compression_t)comp),
            "cannot set the required attributes");
    for (int i = 0; i < img->nchan; i++) {
        exr_pixel_type_t pt = img->chan[i].type == HD_EXR_HALF ? EXR_PIXEL_HALF
                            : img->chan[i].type == HD_EXR_UINT ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
        rv = EXR_CALL(exr_add_channel(ctx, part, img->chan[i].name, pt, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1));
        if (rv != EXR_ERR_SUCCESS) {
            char what[300];
            snprintf(what, sizeof what, "cannot add channel %s", img->chan[i].name);
            st = exr_failure(HD_ERR_IO, name, what, rv);
            goto done;
        }
    }
    if (img->has_chroma) {
        exr_attr_chromaticities_t c = {
            img->chroma[0], img->chroma[1], img->chroma[2], img->chroma[3],
            img->chroma[4], img->chroma[5], img->chroma[6], img->chroma[7]
        };
        EXR_TRY(exr_attr_set_chromaticities(ctx, part, "chromaticities", &c), "cannot set chromaticities");
    }
    for (int i = 0; i < img->nattr; i++)
        EXR_TRY(exr_attr_set_string(ctx, part, img->attr[i].name, img->attr[i].value),
                "cannot set a string attribute");
    EXR_TRY(exr_write_header(ctx), "cannot write the header");

    int32_t lpc = 1;
    EXR_TRY(exr_get_scanlines_per_chunk(ctx, part, &lpc), "cannot get the chunk size");
    if (lpc < 1)
        lpc = 1;
    ubuf = hd_calloc((size_t)img->nchan, sizeof *ubuf);
    if (!ubuf) {
        st = HD_ERR_NOMEM;
        goto done;
    }
    for (int i = 0; i < img->nchan; i++)
        if (img->chan[i].type == HD_EXR_UINT && !(ubuf[i] = to_uint(img, img->chan[i].data))) {
            st = HD_ERR_NOMEM;
            goto done;
        }
    const size_t w = (size_t)img->xres;
    for (int y = 0; y < img->yres; y += lpc) {
        exr_chunk_info_t ci;
        EXR_TRY(exr_write_scanline_chunk_info(ctx, part, y, &ci), "cannot prepare a chunk");
        if (!enc_init) {
            EXR_TRY(exr_encoding_initialize(ctx, part, &ci, &enc), "cannot initialise encoding");
            enc_init = 1;
            map = hd_malloc_array((size_t)enc.channel_count + 1, sizeof *map);
            if (!map) {
                st = HD_ERR_NOMEM;
                goto done;
            }
            for (int c = 0; c < enc.channel_count; c++) {
                map[c] = hd_exr_find_channel(img, enc.channels[c].channel_name);
                if (map[c] < 0) {
                    st = hd_fail(HD_ERR_INTERNAL, "%s: channel %s unknown to the encoder", name,
                                 enc.channels[c].channel_name);
                    goto done;
                }
            }
        } else {
            EXR_TRY(exr_encoding_update(ctx, part, &ci, &enc), "cannot update encoding");
        }
        for (int c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int ic = map[c];
            if (ubuf[ic]) {
                ch->encode_from_ptr = (const uint8_t *)(ubuf[ic] + (size_t)y * w);
                ch->user_data_type = EXR_PIXEL_UINT;
            } else {
                ch->encode_from_ptr = (const uint8_t *)(img->chan[ic].data + (size_t)y * w);
                ch->user_data_type = EXR_PIXEL_FLOAT;
            }
            ch->user_bytes_per_element = 4;
            ch->user_pixel_stride = 4;
            ch->user_line_stride = (int32_t)(4 * w);
        }
        if (y == 0)
            EXR_TRY(exr_encoding_choose_default_routines(ctx, part, &enc), "cannot choose the encoder");
        EXR_TRY(exr_encoding_run(ctx, part, &enc), "cannot encode a chunk");
    }
    if (enc_init) {
        exr_encoding_destroy(ctx, &enc);
        enc_init = 0;
    }
    rv = EXR_CALL(exr_finish(&ctx));
    ctx = NULL;
    if (rv != EXR_ERR_SUCCESS) {
        st = exr_failure(HD_ERR_IO, name, "cannot finish the file", rv);
        goto done;
    }
    if (mb.failed) {
        st = hd_fail(HD_ERR_NOMEM, "%s: cannot assemble the file in memory: %s", name,
                     exr_msg[0] ? exr_msg : "out of memory");
        goto done;
    }
    *data = mb.p;
    *len = mb.len;
    mb.p = NULL;
#undef EXR_TRY
done:
    if (enc_init)
        exr_encoding_destroy(ctx, &enc);
    if (ctx)
        exr_finish(&ctx);
    if (ubuf)
        for (int i = 0; i < img->nchan; i++)
            free(ubuf[i]);
    free(ubuf);
    free(map);
    free(mb.p);
    return st;
}

hd_status hd_exr_write(FILE *fp, const char *name, const hd_exr_image *img, hd_exr_compression comp)
{
    uint8_t *data;
    size_t len;
    hd_status st = hd_exr_encode(img, comp, name, &data, &len);
    if (st != HD_OK)
        return st;
    if (fwrite(data, 1, len, fp) != len)
        st = hd_fail(HD_ERR_IO, "%s: write error", name);
    free(data);
    return st;
}

hd_status hd_exr_save(const char *path, const hd_exr_image *img, hd_exr_compression comp)
{
    hd_ofile *of;
    hd_status st = hd_ofile_open(&of, path);
    if (st != HD_OK)
        return st;
    st = hd_exr_write(hd_ofile_fp(of), (!path || !strcmp(path, "-")) ? "<stdout>" : path, img, comp);
    if (st != HD_OK) {
        hd_ofile_abort(of);
        return st;
    }
    return hd_ofile_commit(of);
}

hd_status hd_exr_write_picture(FILE *fp, const char *name, const hd_picture *p, const hd_header *h)
{
    hd_exr_image img;
    hd_exr_init(&img);
    hd_status st = hd_exr_from_picture(&img, p, NULL, HD_EXR_FLOAT, 1.0);
    if (!st && h && h->len) st = hd_exr_set_attr(&img, HD_EXR_HEADER_ATTR, h->text);
    if (!st) st = hd_exr_write(fp, name, &img, HD_EXR_ZIP);
    hd_exr_free(&img);
    return st;
}

/* ---- reading ---- */

typedef struct memsrc {
    const uint8_t *p;
    size_t len;
} memsrc;

static int64_t mem_read(exr_const_context_t ctxt, void *ud, void *buf, uint64_t sz, uint64_t off,
                        exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    const memsrc *m = ud;
    if (off >= m->len)
        return 0;
    uint64_t n = m->len - off;
    if (n > sz)
        n = sz;
    memcpy(buf, m->p + off, (size_t)n);
    return (int64_t)n;
}

static int64_t mem_size(exr_const_context_t ctxt, void *ud)
{
    (void)ctxt;
    return (int64_t)((const memsrc *)ud)->len;
}

/* Decode the chunks of one part into the image channels (already
 * allocated, map[c] = image channel of pipeline channel c). */
static hd_status decode_chunk(exr_const_context_t ctx, int part, const char *name,
                              const exr_chunk_info_t *ci, exr_decode_pipeline_t *dec, int *dec_init,
                              hd_exr_image *img, int px, int py)
{
    exr_result_t rv;
    if (!*dec_init) {
        rv = EXR_CALL(exr_decoding_initialize(ctx, part, ci, dec));
        if (rv != EXR_ERR_SUCCESS)
            return exr_failure(HD_ERR_FORMAT, name, "cannot initialise decoding", rv);
        *dec_init = 1;
    } else {
        rv = EXR_CALL(exr_decoding_update(ctx, part, ci, dec));
        if (rv != EXR_ERR_SUCCESS)
            return exr_failure(HD_ERR_FORMAT, name, "cannot update decoding", rv);
    }
    if (px < 0 || py < 0 || ci->width < 0 || ci->height < 0 ||
        px + ci->width > img->xres || py + ci->height > img->yres)
        return hd_fail(HD_ERR_FORMAT, "%s: chunk %d (%dx%d at %d,%d) outside the data window",
                       name, ci->idx, ci->width, ci->height, px, py);
    const size_t w = (size_t)img->xres;
    for (int c = 0; c < dec->channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec->channels[c];
        int ic = hd_exr_find_channel(img, ch->channel_name);
        if (ic < 0)
            return hd_fail(HD_ERR_INTERNAL, "%s: channel %s unknown", name, ch->channel_name);
        ch->decode_to_ptr = (uint8_t *)(img->chan[ic].data + (size_t)py * w + (size_t)px);
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_bytes_per_element = 4;
        ch->user_pixel_stride = 4;
        ch->user_line_stride = (int32_t)(4 * w);
    }
    /* Chosen per chunk: a chunk that did not compress is stored raw. */
    {
        rv = EXR_CALL(exr_decoding_choose_default_routines(ctx, part, dec));
        if (rv != EXR_ERR_SUCCESS)
            return exr_failure(HD_ERR_FORMAT, name, "cannot choose the decoder", rv);
    }
    rv = EXR_CALL(exr_decoding_run(ctx, part, dec));
    if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED) {
        int maj = 0, min = 0, pat = 0;
        const char *extra = NULL;
        exr_get_library_version(&maj, &min, &pat, &extra);
        return hd_fail(HD_ERR_UNSUPPORTED, "%s: %s compression cannot be decoded by OpenEXRCore %d.%d.%d "
                       "(re-save the file with another compression, e.g. zip or piz)", name,
                       hd_exr_compression_name((hd_exr_compression)ci->compression), maj, min, pat);
    }
    if (rv != EXR_ERR_SUCCESS) {
        char what[128];
        snprintf(what, sizeof what, "corrupt or truncated pixel data in chunk %d (y %d)",
                 ci->idx, py + img->y0);
        return exr_failure(HD_ERR_FORMAT, name, what, rv);
    }
    return HD_OK;
}

hd_status hd_exr_decode(const void *data, size_t len, const char *name, hd_exr_image *img)
{
    return hd_exr_decode_part(data, len, name, NULL, img);
}

hd_status hd_exr_decode_part(const void *data, size_t len, const char *name, const char *partsel,
                             hd_exr_image *img)
{
    hd_exr_free(img);
    if (!name)
        name = "EXR input";
    if (len < 8 || !hd_exr_is_magic(data))
        return hd_fail(HD_ERR_FORMAT, "%s: not an OpenEXR file (%s)", name,
                       len < 4 ? "shorter than the magic number" : "bad magic number");
    memsrc src = {data, len};
    exr_context_t ctx = NULL;
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int dec_init = 0;
    hd_status st = HD_OK;
    exr_result_t rv;
    exr_context_initializer_t init;
    init_context(&init);
    init.user_data = &src;
    init.read_fn = mem_read;
    init.size_fn = mem_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;

#define EXR_TRY(call, what) do { rv = EXR_CALL(call); \
        if (rv != EXR_ERR_SUCCESS) { st = exr_failure(HD_ERR_FORMAT, name, what, rv); goto done; } } while (0)

    EXR_TRY(exr_start_read(&ctx, name, &init), "cannot read the header");
    int part = 0, nparts = 0;
    EXR_TRY(exr_get_count(ctx, &nparts), "cannot count the parts");
    if (partsel && *partsel) {
        char *end;
        long v = strtol(partsel, &end, 10);
        part = -1;
        if (*end == 0 && v >= 0 && v < nparts)
            part = (int)v;
        for (int i = 0; i < nparts && part < 0; i++) {
            const char *pn = NULL;
            if (EXR_CALL(exr_get_name(ctx, i, &pn)) == EXR_ERR_SUCCESS && pn && !strcmp(pn, partsel))
                part = i;
        }
        if (part < 0) {
            char list[1024];
            size_t used = 0;
            list[0] = 0;
            for (int i = 0; i < nparts && used < sizeof list; i++) {
                const char *pn = NULL;
                exr_get_name(ctx, i, &pn);
                int n = snprintf(list + used, sizeof list - used, "%s%d (%s)", i ? ", " : "", i,
                                 pn ? pn : "unnamed");
                if (n < 0)
                    break;
                used += (size_t)n;
            }
            st = hd_fail(HD_ERR_FORMAT, "%s: no part '%s'; its parts: %s", name, partsel, list);
            goto done;
        }
    } else if (nparts > 1) {
        hd_warn("%s: %d parts; reading only the first", name, nparts);
    }
    img->part = part;
    exr_storage_t storage;
    EXR_TRY(exr_get_storage(ctx, part, &storage), "cannot get the storage type");
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        st = hd_fail(HD_ERR_UNSUPPORTED, "%s: deep images are not supported", name);
        goto done;
    }
    img->tiled = storage == EXR_STORAGE_TILED;
    exr_attr_box2i_t dw;
    EXR_TRY(exr_get_data_window(ctx, part, &dw), "cannot get the data window");
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1 || w > HD_EXR_MAXSIDE || h > HD_EXR_MAXSIDE) {
        st = hd_fail(HD_ERR_RANGE, "%s: data window (%d,%d)-(%d,%d) gives an image of %lldx%lld "
                     "pixels, out of range (1..%d per side)", name, dw.min.x, dw.min.y, dw.max.x,
                     dw.max.y, (long long)w, (long long)h, HD_EXR_MAXSIDE);
        goto done;
    }
    img->xres = (int)w;
    img->yres = (int)h;
    img->x0 = dw.min.x;
    img->y0 = dw.min.y;
    exr_compression_t comp;
    EXR_TRY(exr_get_compression(ctx, part, &comp), "cannot get the compression");
    img->compression = (hd_exr_compression)comp;

    const exr_attr_chlist_t *chl;
    EXR_TRY(exr_get_channels(ctx, part, &chl), "cannot get the channel list");
    if (chl->num_channels < 1) {
        st = hd_fail(HD_ERR_FORMAT, "%s: no channels", name);
        goto done;
    }
    /* Refuse what cannot fit before allocating anything. */
    size_t npix = (size_t)w * (size_t)h, total;
    if (hd_mul_overflow(npix, (size_t)chl->num_channels * sizeof(float), &total) ||
        total > hd_alloc_limit()) {
        st = hd_fail(HD_ERR_NOMEM, "%s: %lldx%lld pixels x %d channels exceed the allocation limit "
                     "(%zu bytes)", name, (long long)w, (long long)h, chl->num_channels, hd_alloc_limit());
        goto done;
    }
    /* A file holds at least its chunk table (8 bytes per chunk): a small
     * file that claims a huge image is refused before the pixels are
     * allocated (the decoder would only find out at the first chunk). */
    int32_t nchunks = 0;
    EXR_TRY(exr_get_chunk_count(ctx, part, &nchunks), "cannot count the chunks");
    if (nchunks < 1 || (uint64_t)nchunks * 8 > (uint64_t)len) {
        st = hd_fail(HD_ERR_FORMAT, "%s: %lldx%lld pixels in %d chunks need a chunk table of %llu bytes, "
                     "the file has %zu bytes (truncated or corrupt)", name, (long long)w, (long long)h,
                     (int)nchunks, (unsigned long long)nchunks * 8, len);
        goto done;
    }
    for (int c = 0; c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            st = hd_fail(HD_ERR_UNSUPPORTED, "%s: channel %.*s is subsampled (%d,%d): not supported",
                         name, e->name.length, e->name.str, e->x_sampling, e->y_sampling);
            goto done;
        }
        char cname[256];
        snprintf(cname, sizeof cname, "%.*s", e->name.length, e->name.str);
        hd_exr_pixtype t = e->pixel_type == EXR_PIXEL_HALF ? HD_EXR_HALF
                         : e->pixel_type == EXR_PIXEL_UINT ? HD_EXR_UINT : HD_EXR_FLOAT;
        if ((st = add_channel_data(img, cname, t, NULL, NULL)) != HD_OK) {
            hd_fail_context(st, "%s", name);
            goto done;
        }
    }

    /* String attributes and chromaticities. */
    int32_t nattr = 0;
    EXR_TRY(exr_get_attribute_count(ctx, part, &nattr), "cannot count the attributes");
    for (int32_t i = 0; i < nattr; i++) {
        const exr_attribute_t *a;
        EXR_TRY(exr_get_attribute_by_index(ctx, part, EXR_ATTR_LIST_FILE_ORDER, i, &a),
                "cannot get an attribute");
        if (a->type == EXR_ATTR_STRING && a->string) {
            char *v = hd_malloc((size_t)a->string->length + 1);
            if (!v) {
                st = HD_ERR_NOMEM;
                goto done;
            }
            memcpy(v, a->string->str, (size_t)a->string->length);
            v[a->string->length] = 0;
            int known = 0;
            for (int k = 0; reserved_attrs[k]; k++)
                known |= !strcmp(a->name, reserved_attrs[k]);
            if (!known)
                st = hd_exr_set_attr(img, a->name, v);
            free(v);
            if (st != HD_OK)
                goto done;
        } else if (a->type == EXR_ATTR_CHROMATICITIES && !strcmp(a->name, "chromaticities")) {
            const exr_attr_chromaticities_t *c = a->chromaticities;
            img->has_chroma = 1;
            img->chroma[0] = c->red_x;
            img->chroma[1] = c->red_y;
            img->chroma[2] = c->green_x;
            img->chroma[3] = c->green_y;
            img->chroma[4] = c->blue_x;
            img->chroma[5] = c->blue_y;
            img->chroma[6] = c->white_x;
            img->chroma[7] = c->white_y;
        }
    }

    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lpc = 1;
        EXR_TRY(exr_get_scanlines_per_chunk(ctx, part, &lpc), "cannot get the chunk size");
        if (lpc < 1)
            lpc = 1;
        for (int64_t yy = 0; yy < h; yy += lpc) {
            exr_chunk_info_t ci;
            int y = (int)(yy + dw.min.y);
            rv = EXR_CALL(exr_read_scanline_chunk_info(ctx, part, y, &ci));
            if (rv != EXR_ERR_SUCCESS) {
                char what[128];
                snprintf(what, sizeof what, "corrupt or truncated file at scanline %d", y);
                st = exr_failure(HD_ERR_FORMAT, name, what, rv);
                goto done;
            }
            if ((st = decode_chunk(ctx, part, name, &ci, &dec, &dec_init, img,
                                   ci.start_x - dw.min.x, ci.start_y - dw.min.y)) != HD_OK)
                goto done;
        }
    } else {
        uint32_t tw, th;
        exr_tile_level_mode_t lm;
        exr_tile_round_mode_t rm;
        EXR_TRY(exr_get_tile_descriptor(ctx, part, &tw, &th, &lm, &rm), "cannot get the tile description");
        if (tw < 1 || th < 1) {
            st = hd_fail(HD_ERR_FORMAT, "%s: tile size %ux%u", name, tw, th);
            goto done;
        }
        int64_t ntx = (w + tw - 1) / tw, nty = (h + th - 1) / th;
        for (int64_t ty = 0; ty < nty; ty++)
            for (int64_t tx = 0; tx < ntx; tx++) {
                exr_chunk_info_t ci;
                rv = EXR_CALL(exr_read_tile_chunk_info(ctx, part, (int)tx, (int)ty, 0, 0, &ci));
                if (rv != EXR_ERR_SUCCESS) {
                    char what[128];
                    snprintf(what, sizeof what, "corrupt or truncated file at tile %lld,%lld",
                             (long long)tx, (long long)ty);
                    st = exr_failure(HD_ERR_FORMAT, name, what, rv);
                    goto done;
                }
                if ((st = decode_chunk(ctx, part, name, &ci, &dec, &dec_init, img,
                                       (int)(tx * tw), (int)(ty * th))) != HD_OK)
                    goto done;
            }
    }
#undef EXR_TRY
done:
    if (dec_init)
        exr_decoding_destroy(ctx, &dec);
    if (ctx)
        exr_finish(&ctx);
    if (st != HD_OK)
        hd_exr_free(img);
    return st;
}

hd_status hd_exr_load(const char *path, hd_exr_image *img)
{
    return hd_exr_load_part(path, NULL, img);
}

hd_status hd_exr_load_part(const char *path, const char *partsel, hd_exr_image *img)
{
    hd_istream *s;
    hd_status st = hd_istream_open(&s, path);
    if (st != HD_OK)
        return st;
    const char *name = hd_istream_name(s);
    uint8_t *buf = NULL;
    size_t len = 0;
    st = hd_istream_read_all(s, &buf, &len);
    if (st == HD_OK)
        st = hd_exr_decode_part(buf, len, name, partsel, img);
    free(buf);
    {
        hd_status st2 = hd_istream_close(s);
        if (st == HD_OK && st2 != HD_OK) {
            hd_exr_free(img);
            st = st2;
        }
    }
    return st;
}

/* ---- conversions with pictures ---- */

static void layer_channel(char *buf, size_t cap, const char *layer, const char *c)
{
    if (layer && *layer)
        snprintf(buf, cap, "%s.%s", layer, c);
    else
        snprintf(buf, cap, "%s", c);
}

static int parse_primaries(const hd_header *h, float out[8])
{
    char buf[512];
    if (!hd_header_get(h, "PRIMARIES", buf, sizeof buf))
        return 0;
    char *p = buf;
    for (int i = 0; i < 8; i++) {
        char *e;
        double v = strtod(p, &e);
        if (e == p || !isfinite(v))
            return 0;
        out[i] = (float)v;
        p = e;
    }
    return 1;
}

hd_status hd_exr_from_picture(hd_exr_image *img, const hd_picture *p, const char *layer,
                              hd_exr_pixtype type, double scale)
{
    hd_status st;
    if (img->nchan == 0) {
        if ((st = hd_exr_set_size(img, p->xres, p->yres)) != HD_OK)
            return st;
    } else if (img->xres != p->xres || img->yres != p->yres) {
        return hd_fail(HD_ERR_RANGE, "picture of %dx%d does not match the EXR image size %dx%d",
                       p->xres, p->yres, img->xres, img->yres);
    }
    static const char *const rgb[3] = {"R", "G", "B"};
    int idx[3];
    for (int k = 0; k < 3; k++) {
        char cname[300];
        layer_channel(cname, sizeof cname, layer, rgb[k]);
        if ((st = hd_exr_add_channel(img, cname, type, &idx[k])) != HD_OK)
            return st;
    }
    size_t n = (size_t)p->xres * (size_t)p->yres, nclamp = 0;
    for (int k = 0; k < 3; k++) {
        float *d = img->chan[idx[k]].data;
        for (size_t i = 0; i < n; i++) {
            double v = p->pix[3 * i + k] * scale;
            if (type == HD_EXR_HALF && fabs(v) > HD_EXR_HALF_MAX) {
                v = v > 0 ? HD_EXR_HALF_MAX : -HD_EXR_HALF_MAX;
                nclamp++;
            }
            d[i] = (float)v;
        }
    }
    if (nclamp)
        hd_warn("%zu values beyond the half-float range clamped to %g (use float channels to keep them)",
                nclamp, HD_EXR_HALF_MAX);
    if (!img->has_chroma) {
        img->has_chroma = 1;
        if (p->fmt == HD_PIC_XYZE)
            memcpy(img->chroma, hd_exr_chroma_xyz, sizeof img->chroma);
        else if (!parse_primaries(&p->hdr, img->chroma))
            memcpy(img->chroma, hd_exr_chroma_radiance, sizeof img->chroma);
    }
    return HD_OK;
}

void hd_exr_list_layers(const hd_exr_image *img, char *buf, size_t cap)
{
    size_t used = 0;
    if (cap == 0)
        return;
    buf[0] = 0;
    for (int i = 0; i < img->nchan; i++) {
        const char *nm = img->chan[i].name, *dot = strrchr(nm, '.');
        int llen = dot ? (int)(dot - nm) : 0;
        /* already listed? */
        int seen = 0;
        for (int j = 0; j < i && !seen; j++) {
            const char *o = img->chan[j].name, *od = strrchr(o, '.');
            int ol = od ? (int)(od - o) : 0;
            seen = ol == llen && !strncmp(o, nm, (size_t)llen);
        }
        if (seen)
            continue;
        int n = snprintf(buf + used, cap - used, "%s%.*s", used ? ", " : "",
                         llen ? llen : 9, llen ? nm : "(default)");
        if (n < 0 || (size_t)n >= cap - used)
            return;
        used += (size_t)n;
    }
}

static int chroma_equal(const float a[8], const float b[8])
{
    for (int i = 0; i < 8; i++)
        if (fabsf(a[i] - b[i]) > 1e-4f)
            return 0;
    return 1;
}

hd_status hd_exr_header_add_primaries(const hd_exr_image *img, hd_header *h)
{
    if (!img->has_chroma || chroma_equal(img->chroma, hd_exr_chroma_xyz))
        return HD_OK;
    float cur[8];
    if (!parse_primaries(h, cur))
        memcpy(cur, hd_exr_chroma_radiance, sizeof cur);
    if (chroma_equal(img->chroma, cur))
        return HD_OK;
    return hd_header_appendf(h, "PRIMARIES= %.4f %.4f %.4f %.4f %.4f %.4f %.4f %.4f",
                             img->chroma[0], img->chroma[1], img->chroma[2], img->chroma[3],
                             img->chroma[4], img->chroma[5], img->chroma[6], img->chroma[7]);
}

hd_status hd_exr_to_picture(const hd_exr_image *img, const char *layer, hd_picture *p)
{
    static const char *const rgb[3] = {"R", "G", "B"};
    int idx[3];
    char cname[300];
    int found = 0;
    for (int k = 0; k < 3; k++) {
        layer_channel(cname, sizeof cname, layer, rgb[k]);
        idx[k] = hd_exr_find_channel(img, cname);
        found += idx[k] >= 0;
    }
    if (found != 3) {
        layer_channel(cname, sizeof cname, layer, "Y");
        int y = hd_exr_find_channel(img, cname);
        if (found == 0 && y >= 0) {
            idx[0] = idx[1] = idx[2] = y;
        } else {
            char layers[1024];
            hd_exr_list_layers(img, layers, sizeof layers);
            const char *l = layer && *layer ? layer : "", *d = *l ? "." : "";
            return hd_fail(HD_ERR_FORMAT, "no channels %s%sR, %s%sG, %s%sB (or %s%sY) in the EXR image; "
                           "its layers: %s", l, d, l, d, l, d, l, d, layers);
        }
    }
    hd_status st = hd_picture_alloc(p, img->xres, img->yres);
    if (st != HD_OK)
        return st;
    size_t n = (size_t)img->xres * (size_t)img->yres, nbad = 0;
    for (int k = 0; k < 3; k++) {
        const float *d = img->chan[idx[k]].data;
        for (size_t i = 0; i < n; i++) {
            float v = d[i];
            if (isnan(v)) {
                v = 0.0f;
                nbad++;
            } else if (v > 1e38f) {     /* largest RGBE exponent */
                v = 1e38f;
                nbad++;
            }
            p->pix[3 * i + k] = v;
        }
    }
    if (nbad)
        hd_warn("%zu NaN or out-of-range values set to 0 (NaN) or 1e38", nbad);
    p->fmt = img->has_chroma && chroma_equal(img->chroma, hd_exr_chroma_xyz) ? HD_PIC_XYZE : HD_PIC_RGBE;
    return HD_OK;
}

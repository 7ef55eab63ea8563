/* hdr2exr — convert Radiance pictures to an OpenEXR image.
 *
 *   hdr2exr [-half|-float] [-c none|rle|zips|zip|piz] [-r] [in.hdr|-] out.exr
 *   hdr2exr [-half|-float] [-c ...] [-r] -L layer in.hdr [-L layer in.hdr ...] out.exr
 *
 * See docs/man/hdr2exr.1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/options.h"
#include "heliodon/picture.h"

#define SYNOPSIS "[-half|-float] [-c none|rle|zips|zip|piz] [-r] {[in.hdr|-] | -L layer in.hdr ...} out.exr"
#define MAXLAYERS 256

typedef struct conf {
    hd_exr_pixtype type;
    int nlayers;
    const char *layer[MAXLAYERS];
    const char *input[MAXLAYERS];
} conf;

static int opt_type(const hd_opt *o, int argc, char **argv, int i, void *ctx)
{
    (void)argc;
    (void)argv;
    (void)i;
    ((conf *)ctx)->type = !strcmp(o->name, "half") ? HD_EXR_HALF : HD_EXR_FLOAT;
    return 0;
}

static int opt_layer(const hd_opt *o, int argc, char **argv, int i, void *ctx)
{
    (void)o;
    conf *c = ctx;
    if (i + 2 >= argc) {
        hd_fail(HD_ERR_USAGE, "-L needs a layer name and a picture");
        return -1;
    }
    if (c->nlayers >= MAXLAYERS) {
        hd_fail(HD_ERR_USAGE, "more than %d layers", MAXLAYERS);
        return -1;
    }
    c->layer[c->nlayers] = argv[i + 1];
    c->input[c->nlayers] = argv[i + 2];
    c->nlayers++;
    return 2;
}

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    conf c = {HD_EXR_FLOAT, 0, {0}, {0}};
    const char *compname = "zip";
    int raw = 0;
    const hd_opt table[] = {
        {"half", HD_OPT_FUNC, &c, opt_type, 0, NULL, "half-float channels (16 bits; values beyond 65504 clamped)"},
        {"float", HD_OPT_FUNC, &c, opt_type, 0, NULL, "32-bit float channels (default)"},
        {"c", HD_OPT_STRING, &compname, NULL, 0, "comp", "compression: none, rle, zips, zip (default), piz"},
        {"r", HD_OPT_TOGGLE, &raw, NULL, 0, NULL, "keep values as stored (do not undo EXPOSURE)"},
        {"L", HD_OPT_FUNC, &c, opt_layer, 0, "layer in.hdr", "add a picture as channels layer.R, layer.G, layer.B"},
        HD_OPT_END
    };
    hd_optparse op;
    hd_opt_parse_or_exit(&op, argc, argv, table, SYNOPSIS);
    int nops = op.argc - op.first;
    hd_exr_compression comp;
    if (hd_exr_parse_compression(compname, &comp)) {
        hd_fail(HD_ERR_USAGE, "unknown compression '%s' (none, rle, zips, zip, piz)", compname);
        hd_opt_usage(table, SYNOPSIS);
        hd_optparse_free(&op);
        return 1;
    }
    const char *out;
    if (c.nlayers > 0) {
        if (nops != 1) {
            hd_fail(HD_ERR_USAGE, "with -L, give only the output file");
            hd_opt_usage(table, SYNOPSIS);
            hd_optparse_free(&op);
            return 1;
        }
        out = op.argv[op.first];
    } else {
        if (nops < 1 || nops > 2) {
            hd_fail(HD_ERR_USAGE, nops < 1 ? "missing output file" : "too many arguments");
            hd_opt_usage(table, SYNOPSIS);
            hd_optparse_free(&op);
            return 1;
        }
        c.layer[0] = NULL;
        c.input[0] = nops == 2 ? op.argv[op.first] : "-";
        c.nlayers = 1;
        out = op.argv[op.first + nops - 1];
    }

    hd_exr_image img;
    hd_exr_init(&img);
    hd_header h;
    hd_header_init(&h);
    for (int i = 0; i < c.nlayers; i++) {
        hd_picture p;
        hd_picture_init(&p);
        if (hd_picture_read(c.input[i], &p) != HD_OK)
            hd_die();
        double scale = 1.0;
        if (!raw) {
            double e = hd_header_exposure(&p.hdr);
            if (!(e > 0))
                hd_die_msg("%s: bad EXPOSURE %g", c.input[i], e);
            scale = 1.0 / e;
            hd_header_remove(&p.hdr, "EXPOSURE");
        }
        if (hd_exr_from_picture(&img, &p, c.layer[i], c.type, scale) != HD_OK) {
            hd_fail_context(HD_ERR_FORMAT, "%s", c.input[i]);
            hd_die();
        }
        /* provenance: the input's header lines; with -L, one attribute
         * heliodonHeader.LAYER per layer */
        hd_header_remove(&p.hdr, "FORMAT");
        if (c.layer[i]) {
            char aname[300];
            snprintf(aname, sizeof aname, "%s.%s", HD_EXR_HEADER_ATTR, c.layer[i]);
            if (hd_exr_set_attr(&img, aname, p.hdr.text ? p.hdr.text : "") != HD_OK)
                hd_die();
        } else if (hd_header_copy(&h, &p.hdr) != HD_OK) {
            hd_die();
        }
        hd_picture_free(&p);
    }
    if (hd_header_add_command(&h, argc, argv) != HD_OK || hd_header_add_software(&h) != HD_OK)
        hd_die();
    if (hd_exr_set_attr(&img, HD_EXR_HEADER_ATTR, h.text ? h.text : "") != HD_OK)
        hd_die();
    if (hd_exr_save(out, &img, comp) != HD_OK)
        hd_die();
    hd_header_free(&h);
    hd_exr_free(&img);
    hd_optparse_free(&op);
    return 0;
}

/* exr2hdr — convert an OpenEXR image (or one of its layers) to a Radiance
 * picture.
 *
 *   exr2hdr [-p part] [-l layer] in.exr|- [out.hdr|-]
 *
 * See docs/man/exr2hdr.1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/common.h"
#include "heliodon/exr.h"
#include "heliodon/header.h"
#include "heliodon/options.h"
#include "heliodon/picture.h"

#define SYNOPSIS "[-p part] [-l layer] in.exr|- [out.hdr|-]"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    const char *layer = NULL, *part = NULL;
    const hd_opt table[] = {
        {"l", HD_OPT_STRING, &layer, NULL, 0, "layer", "convert channels layer.R, layer.G, layer.B"},
        {"p", HD_OPT_STRING, &part, NULL, 0, "part", "read the part of that name or number (default: the first)"},
        HD_OPT_END
    };
    hd_optparse op;
    hd_opt_parse_or_exit(&op, argc, argv, table, SYNOPSIS);
    int nops = op.argc - op.first;
    if (nops < 1 || nops > 2) {
        hd_fail(HD_ERR_USAGE, nops < 1 ? "missing input file" : "too many arguments");
        hd_opt_usage(table, SYNOPSIS);
        hd_optparse_free(&op);
        return 1;
    }
    const char *in = op.argv[op.first];
    const char *out = nops == 2 ? op.argv[op.first + 1] : "-";

    hd_exr_image img;
    hd_exr_init(&img);
    if (hd_exr_load_part(in, part, &img) != HD_OK)
        hd_die();
    hd_picture p;
    hd_picture_init(&p);
    if (hd_exr_to_picture(&img, layer, &p) != HD_OK) {
        hd_fail_context(HD_ERR_FORMAT, "%s", in);
        hd_die();
    }
    hd_header h;
    hd_header_init(&h);
    /* the lines carried from the original header(s): the layer's own
     * (heliodonHeader.LAYER), then the common ones (heliodonHeader) */
    char aname[300];
    snprintf(aname, sizeof aname, "%s.%s", HD_EXR_HEADER_ATTR, layer ? layer : "");
    const char *prov[2] = {layer && *layer ? hd_exr_get_attr(&img, aname) : NULL,
                           hd_exr_get_attr(&img, HD_EXR_HEADER_ATTR)};
    for (int k = 0; k < 2; k++) {
        const char *s = prov[k];
        while (s && *s) {
            const char *e = strchr(s, '\n');
            size_t n = e ? (size_t)(e - s) : strlen(s);
            if (n > 0 && hd_header_appendf(&h, "%.*s", (int)n, s) != HD_OK)
                hd_die();
            s += n + (e != NULL);
        }
    }
    hd_header_remove(&h, "FORMAT");
    if (hd_exr_header_add_primaries(&img, &h) != HD_OK)
        hd_die();
    if (hd_header_add_command(&h, argc, argv) != HD_OK || hd_header_add_software(&h) != HD_OK)
        hd_die();
    if (hd_picture_save(out, &p, &h) != HD_OK)
        hd_die();
    hd_header_free(&h);
    hd_picture_free(&p);
    hd_exr_free(&img);
    hd_optparse_free(&op);
    return 0;
}

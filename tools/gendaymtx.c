/* gendaymtx — annual sky matrix from a WEA or EPW weather file (Radiance
 * compatible).  See docs/man/gendaymtx.1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/header.h"
#include "heliodon/io.h"
#include "heliodon/options.h"
#include "heliodon/sky.h"
#include "heliodon/weather.h"

static const char *synopsis =
    "[-v][-h][-A][-d|-s|-n][-u][-D sunfile][-M sunmods][-r deg][-m N][-g r g b][-c r g b]"
    "[-o{f|d|a}][-O{0|1}][-5 diam][-i min][-nt N] [weather.wea|weather.epw]";

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_daymtx_job job;
    memset(&job, 0, sizeof job);
    hd_daymtx_opts_default(&job.o);
    job.mf = 1;
    job.warnings = 1;
    int verbose = 0, noheader = 0, average = 0, sun_only = 0, sky_only = 0, nomatrix = 0, skip_night = 0;
    double rot = 0, rotz = 0, disk = 0;
    const char *ofmt = NULL, *Ofmt = NULL, *sunfile = NULL, *modfile = NULL;
    int nthreads = 0, nowarn = 0;
    const hd_opt table[] = {
        {"v", HD_OPT_TOGGLE, &verbose, 0, 0, 0, "verbose"},
        {"h", HD_OPT_TOGGLE, &noheader, 0, 0, 0, "no header"},
        {"A", HD_OPT_TOGGLE, &average, 0, 0, 0, "one column: the average sky"},
        {"d", HD_OPT_TOGGLE, &sun_only, 0, 0, 0, "direct sun only"},
        {"s", HD_OPT_TOGGLE, &sky_only, 0, 0, 0, "sky only (no direct sun)"},
        {"n", HD_OPT_TOGGLE, &nomatrix, 0, 0, 0, "no matrix output"},
        {"u", HD_OPT_TOGGLE, &skip_night, 0, 0, 0, "omit time steps with the sun below the horizon"},
        {"D", HD_OPT_STRING, &sunfile, 0, 0, "file", "write sun descriptions (- = stdout, implies -n)"},
        {"M", HD_OPT_STRING, &modfile, 0, 0, "file", "write sun modifier names"},
        {"r", HD_OPT_REAL, &rot, 0, 0, "deg", "rotate the sky counter-clockwise about the zenith"},
        {"rz", HD_OPT_REAL, &rotz, 0, 0, "deg", "same as -r"},
        {"m", HD_OPT_INT, &job.mf, 0, 0, "N", "Reinhart subdivision MF:N (1 = Tregenza)"},
        {"g", HD_OPT_REAL3, job.o.grefl, 0, 0, "r g b", "ground reflectance"},
        {"c", HD_OPT_REAL3, job.o.skycolor, 0, 0, "r g b", "sky colour"},
        {"o", HD_OPT_STRING, &ofmt, 0, 1, 0, "-of float, -od double, -oa ascii output"},
        {"O", HD_OPT_STRING, &Ofmt, 0, 1, 0, "-O0 visible (default), -O1 solar radiance"},
        {"5", HD_OPT_REAL, &disk, 0, 0, "diam", "sun in one patch with the radiance of a disk of diam degrees"},
        {"nt", HD_OPT_INT, &nthreads, 0, 0, "N", "threads (0 = all processors)"},
        {"i", HD_OPT_REAL, &job.o.interval_min, 0, 0, "min", "time-step length for the sunrise/sunset correction"},
        {"w", HD_OPT_TOGGLE, &nowarn, 0, 0, 0, "no warnings"},
        HD_OPT_END};
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, synopsis);
    if (nowarn) hd_set_warnings(0);

    enum { F_ASCII, F_FLOAT, F_DOUBLE } fmt = F_ASCII;
    static const char *fmtname[3] = {"ascii", "float", "double"};
    if (ofmt) {
        const char *f = ofmt + 2;   /* "-of" */
        if (!strcmp(f, "f")) fmt = F_FLOAT;
        else if (!strcmp(f, "d")) fmt = F_DOUBLE;
        else if (!strcmp(f, "a")) fmt = F_ASCII;
        else hd_die_msg("bad output format option %s (expected -of, -od or -oa)", ofmt);
    }
    if (Ofmt) {
        const char *f = Ofmt + 2;
        if (!strcmp(f, "0")) job.o.solar_output = 0;
        else if (!strcmp(f, "1")) job.o.solar_output = 1;
        else hd_die_msg("bad output type option %s (expected -O0 or -O1)", Ofmt);
    }
    if (sun_only && sky_only) hd_die_msg("options -d and -s exclude each other");
    if (job.mf < 1 || job.mf > HD_SKY_MAXMF) hd_die_msg("-m %d: subdivision must be 1..%d", job.mf, HD_SKY_MAXMF);
    if (job.o.interval_min < 0 || job.o.interval_min > 1440) hd_die_msg("-i %g: minutes out of range 0..1440", job.o.interval_min);
    if (disk < 0 || disk > 30) hd_die_msg("-5 %g: disk diameter must be in (0,30] degrees", disk);
    job.o.sun_only = sun_only;
    job.o.sky_only = sky_only;
    job.o.disk_deg = disk;
    job.o.rotation_deg = rot + rotz;
    job.skip_night = skip_night;
    job.average = average;
    job.nthreads = nthreads;
    if (p.argc - p.first > 1) hd_die_msg("too many arguments (expected one weather file)");
    const char *wfile = p.first < p.argc ? p.argv[p.first] : "-";

    hd_weather w;
    if (hd_weather_read(wfile, &w)) hd_die();
    if (verbose)
        fprintf(stderr, "%s: location '%s', latitude %.2f N, longitude %.2f E, %zu time steps, MF:%d\n",
                hd_progname(), w.place, w.site.lat, -w.site.lon, w.n, job.mf);

    hd_header h;
    hd_header_init(&h);
    if (hd_header_add_command(&h, argc, argv)) hd_die();
    char *cmdline = hd_strdup(h.text ? h.text : "");
    if (cmdline && *cmdline) cmdline[strlen(cmdline) - 1] = 0;

    if (sunfile || modfile) {
        int to_stdout = sunfile && !strcmp(sunfile, "-");
        if (to_stdout) nomatrix = 1;
        hd_ofile *rf = NULL, *mf = NULL;
        if (sunfile && hd_ofile_open(&rf, to_stdout ? NULL : sunfile)) hd_die();
        if (modfile && hd_ofile_open(&mf, modfile)) hd_die();
        if (hd_daymtx_write_suns(rf ? hd_ofile_fp(rf) : NULL, mf ? hd_ofile_fp(mf) : NULL, &w, &job, cmdline))
            hd_die();
        if (rf && hd_ofile_commit(rf)) hd_die();
        if (mf && hd_ofile_commit(mf)) hd_die();
    }
    free(cmdline);
    if (nomatrix) {
        hd_header_free(&h);
        hd_weather_free(&w);
        hd_optparse_free(&p);
        return 0;
    }

    /* -A: the averaged column; otherwise the compact store written row by row */
    hd_daymtx_result r;
    hd_daymtx_store ms;
    memset(&r, 0, sizeof r);
    memset(&ms, 0, sizeof ms);
    if (average) {
        if (hd_daymtx_generate(&w, &job, &r)) hd_die();
    } else {
        if (hd_daymtx_compute(&w, &job, &ms)) hd_die();
        r.nbins = ms.nbins;
        r.ncols = ms.ncols;
    }
    hd_ofile *of;
    if (hd_ofile_open(&of, NULL)) hd_die();
    FILE *fp = hd_ofile_fp(of);
    if (!noheader) {
        hd_header_appendf(&h, "LATLONG= %.8f %.8f", w.site.lat, -w.site.lon);
        hd_header_appendf(&h, "NROWS=%d", r.nbins);
        hd_header_appendf(&h, "NCOLS=%d", r.ncols);
        if (average) hd_header_appendf(&h, "NAVERAGED=%ld", r.naveraged);
        hd_header_dims d = {0, 0, 3, fmt != F_ASCII ? HD_ENDIAN_HOST : HD_ENDIAN_NONE};
        if (hd_header_put(fp, &h, &d, fmtname[fmt], NULL)) hd_die();
    }
    hd_status st = HD_OK;
    size_t nval = (size_t)r.nbins * (size_t)r.ncols * 3;
    if (!average) {
        st = hd_daymtx_store_write(fp, &ms, fmt == F_ASCII ? HD_DAYMTX_ASCII : fmt == F_FLOAT ? HD_DAYMTX_FLOAT
                                                                                           : HD_DAYMTX_DOUBLE);
    } else if (fmt == F_ASCII) {
        st = hd_daymtx_write_ascii(fp, &r);
    } else if (fmt == F_FLOAT) {
        if (fwrite(r.data, sizeof(float), nval, fp) != nval) st = hd_fail(HD_ERR_IO, "write error on stdout");
    } else {
        for (size_t i = 0; i < nval && !st; i++) {
            double v = r.data[i];
            if (fwrite(&v, sizeof v, 1, fp) != 1) st = hd_fail(HD_ERR_IO, "write error on stdout");
        }
    }
    if (st || hd_ofile_commit(of)) hd_die();
    hd_daymtx_result_free(&r);
    hd_daymtx_store_free(&ms);
    hd_header_free(&h);
    hd_weather_free(&w);
    hd_optparse_free(&p);
    return 0;
}

/* cbdmreport — static HTML report (heat maps, histograms, shade schedule,
 * false-colour hours, parameters, timings) of an annual glare run; also
 * picks the hours to show (-select) and verifies PNG files (-check). */
#include <stdio.h>
#include <string.h>

#include "heliodon/options.h"
#include "heliodon/report.h"

int main(int argc, char **argv)
{
    hd_set_progname(argv[0]);
    hd_report_opts o;
    hd_report_opts_default(&o);
    const char *select = NULL, *png = NULL;
    int nselect = 3, check = 0;
    const hd_opt table[] = {
        {"c", HD_OPT_STRING, &o.csv, 0, 0, "annual.csv", "glare CSV of pmcompose or glarestats"},
        {"o", HD_OPT_STRING, &o.outdir, 0, 0, "dir", "report directory (index.html and figures)"},
        {"p", HD_OPT_STRING, &o.params, 0, 0, "file", "run parameters (\"key = value\" lines)"},
        {"T", HD_OPT_STRING, &o.timings, 0, 0, "file", "stage timings (\"stage seconds\" lines)"},
        {"N", HD_OPT_STRING, &o.summary, 0, 0, "file", "notes shown verbatim"},
        {"title", HD_OPT_STRING, &o.title, 0, 0, "text", "page title"},
        {"open", HD_OPT_STRING, &o.open_csv, 0, 0, "open.csv",
         "two-pass shade: the open run's CSV (-c is then pmcompose -schedule's composite)"},
        {"s", HD_OPT_REAL, &o.shade_limit, 0, 0, "dgp", "shade closes when DGP >= this (0.40)"},
        {"lmin", HD_OPT_REAL, &o.lmin, 0, 0, "cd/m2", "false-colour scale minimum (10)"},
        {"lmax", HD_OPT_REAL, &o.lmax, 0, 0, "cd/m2", "false-colour scale maximum (10000)"},
        {"select", HD_OPT_STRING, &select, 0, 0, "hourlog", "print the records to show (max, p95, median DGP)"},
        {"n", HD_OPT_INT, &nselect, 0, 0, "N", "number of records for -select (3)"},
        {"png", HD_OPT_STRING, &png, 0, 0, "out.png",
         "write the display picture operand (e.g. falsecolor's) as PNG, gamma 2.2"},
        {"check", HD_OPT_TOGGLE, &check, 0, 0, NULL, "verify the PNG files given as operands"},
        HD_OPT_END};
    const char *syn = "-c annual.csv -o dir [-p params][-T timings][hour.hdr ...] | -select log | -check f.png ... | -png out.png picture";
    hd_optparse p;
    hd_opt_parse_or_exit(&p, argc, argv, table, syn);
    if (check) {
        if (p.argc == p.first) hd_die_msg("-check: no PNG files given");
        for (int i = p.first; i < p.argc; i++) {
            int w, h;
            if (hd_png_read(p.argv[i], NULL, &w, &h)) hd_die();
            printf("%s: PNG %d x %d OK\n", p.argv[i], w, h);
        }
        hd_optparse_free(&p);
        return 0;
    }
    if (png) {
        if (p.argc != p.first + 1) hd_die_msg("-png: expected one picture operand");
        if (hd_report_display_png(p.argv[p.first], png)) hd_die();
        hd_optparse_free(&p);
        return 0;
    }
    if (select) {
        if (hd_report_select(select, nselect, stdout)) hd_die();
        hd_optparse_free(&p);
        return 0;
    }
    if (!o.csv || !o.outdir) {
        hd_opt_usage(table, syn);
        return 1;
    }
    if (!(o.lmin > 0) || !(o.lmax > o.lmin)) hd_die_msg("-lmin/-lmax: need 0 < lmin < lmax");
    o.images = (const char **)(p.argv + p.first);
    o.nimages = p.argc - p.first;
    if (hd_report_write(&o)) hd_die();
    printf("%s/index.html\n", o.outdir);
    hd_optparse_free(&p);
    return 0;
}

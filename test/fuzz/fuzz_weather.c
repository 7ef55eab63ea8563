/* Fuzz harness: weather files (WEA header and records, EPW location line,
 * DATA PERIODS and hourly records), parsed from memory, then the derived
 * values and the WEA writer. */
#include <stdio.h>

#include "fuzz.h"
#include "heliodon/weather.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hd_fuzz_setup();
    hd_weather w;
    if (hd_weather_read_memory((const char *)data, size, "fuzz.wea", &w) == HD_OK) {
        double acc = 0;
        for (size_t i = 0; i < w.n && i < 64; i++) acc += hd_weather_dewpoint(&w, i);
        volatile double sink = acc;
        (void)sink;
        FILE *fp = fopen("/dev/null", "w");
        if (fp) {
            (void)hd_weather_write_wea(fp, &w);
            fclose(fp);
        }
    }
    hd_weather_free(&w);
    return 0;
}

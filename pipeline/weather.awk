# weather.awk: the records of a WEA or EPW weather file (heliodon-pipeline(7); methods.mk).
#   awk -v site=SITE.txt -f weather.awk WEATHER > records.txt
# records.txt: "record month day hour DNI DHI" for every record, record counted from 0 over all
# records as pmcompose counts them; EPW hours are the hour ending - 0.5 (the middle of the hour).
# SITE.txt: "latitude longitude meridian" in gendaylit's convention (degrees north, west, west):
# a WEA file's header values, an EPW's LOCATION line with east longitude and UTC offset negated.
FNR == 1 { epw = ($0 ~ /^LOCATION,/) }
epw && FNR == 1 { split($0, f, ","); printf "%s %s %s\n", f[7] + 0, -f[8], -15 * f[9] > site }
epw && FNR > 8 { split($0, f, ","); print n++, f[2] + 0, f[3] + 0, f[4] - 0.5, f[15] + 0, f[16] + 0 }
!epw && /^latitude/ { lat = $2 + 0 }
!epw && /^longitude/ { lon = $2 + 0 }
!epw && /^time_zone/ { mer = $2 + 0 }
!epw && data && NF >= 5 { print n++, $1 + 0, $2 + 0, $3 + 0, $4 + 0, $5 + 0 }
!epw && /^weather_data_file_units/ { data = 1; printf "%s %s %s\n", lat, lon, mer > site }

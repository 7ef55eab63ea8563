# heliodon pipeline: the methods beside PM-CBDM (included by heliodon.mk; heliodon-pipeline(7)).
#
#   METHOD=pm         PM-CBDM (the default; heliodon.mk's own stages, outputs in OUT/VIEW/)
#   METHOD=3pm        the plain three-phase method with the sun: sky AND sun through V T D s per
#                     window group (Klems T = KLEMS_<group>, the sky vectors of gendaymtx without
#                     -s/-d: the sun shared among its nearest patches), composed per hour by
#                     pmcompose -sunsky into the same glare evaluation and report; OUT/3pm/
#   METHOD=5pm        the five-phase method (the paper's Appendix A): the 3PM series minus its direct
#                     sun (black-interior V times the reflectance map, -ab 0 D, sun-only sky vectors)
#                     plus MF:6 direct-sun coefficients times the map and the sun seen through the
#                     windows; pipeline/fivephase.mk, OUT/5pm/
#   METHOD=imageless  Radiance's imageless annual glare (dcglare): eye-illuminance DCs (total and
#                     direct-only) of each glare view's eye point and direction, the sky matrix with
#                     the sun in its patches; hourly DGPs, and its hour-by-hour agreement with the
#                     image-based PM-CBDM result when that exists; OUT/imageless/
# Every method writes under its own folder, so the methods share one run folder (the scene, the
# view matrices V of OUT/VIEW/v and the preflight are shared).  "make" builds the METHOD's report;
# "make compare" the table of every method present.

METHOD       ?= pm
KLEMS_GLASS_C ?= 1000
IMGL_DIRECT_OPTS ?= -ab 1 -ad 20000 -lw 2e-5
IMGL_OPTS    ?= -ab 5 -ad 16384 -lw 1e-5
IMGL_B       ?= 2000
D3_OPTS      ?= $(D_OPTS)

HD_METHODS := pm 3pm imageless 5pm
$(if $(filter-out 1,$(words $(METHOD))),$(error heliodon-pipeline: METHOD='$(METHOD)': expected one of $(HD_METHODS)))
$(if $(filter $(METHOD),$(HD_METHODS)),,$(error heliodon-pipeline: METHOD='$(METHOD)': expected one of $(HD_METHODS)))
ifneq ($(METHOD),pm)
$(if $(HD_SHADE),$(error heliodon-pipeline: METHOD=$(METHOD): the two-pass operated shade (CLOSED_<group>) is PM-CBDM only))
$(if $(HD_GLARE),,$(error heliodon-pipeline: METHOD=$(METHOD): no glare view (a 180-degree fisheye view in VIEWS or GLARE_VIEWS)))
.DEFAULT_GOAL := method
endif
.PHONY: method compare hd_force
# view file of a glare view name
hd_vfile = $(firstword $(foreach v,$(GLARE_VIEWS),$(if $(filter $(1),$(call hd_vname,$(v))),$(v))))

# ================================================================= plain 3PM with the sun
M3 = $(OUT)/3pm
hd_klems = $(if $(filter glass,$(KLEMS_$(1))),$(M3)/glass_klems.xml,$(KLEMS_$(1)))
$(M3)/preflight.ok: $(OUT)/preflight.ok
	@mkdir -p $(M3)
	@$(foreach g,$(GROUPS),k='$(KLEMS_$(g))'; { [ "$$k" = glass ] || { [ -n "$$k" ] && [ -r "$$k" ]; }; } || \
	  { echo "heliodon-pipeline: group '$(g)': METHOD=3pm: Klems BSDF for $(g) not found (KLEMS_$(g)='$$k'; 'glass' makes a clear pane's)" >&2; exit 1; };)
	@touch $@
# a single clear pane (glass transmissivity .96, the pipeline's MAT_<group>=glass) as Klems BSDF
$(M3)/glass_klems.xml: $(M3)/preflight.ok
	printf 'void glass pane_glass 0 0 3 .96 .96 .96\npane_glass polygon pane 0 0 12 -1000 -1000 -2 1000 -1000 -2 1000 1000 -2 -1000 1000 -2\n' > $(M3)/pane.rad
	genBSDF -c $(KLEMS_GLASS_C) +f +b -n $(NPROC) -geom millimeter -dim -50 50 -50 50 -4 0 $(M3)/pane.rad > $@.tmp && $(commit)
# receiver of the daylight matrices: ground (bin 0) and the Reinhart MF:SKYMF sky
$(M3)/sky_rx.rad: $(M3)/preflight.ok
	{ echo "#@rfluxmtx h=u u=Y"; echo "void glow groundglow 0 0 4 1 1 1 0"; echo "groundglow source ground 0 0 4 0 0 -1 180"; \
	  echo "#@rfluxmtx h=r$(SKYMF) u=Y"; echo "void glow skyglow 0 0 4 1 1 1 0"; echo "skyglow source skydome 0 0 4 0 0 1 180"; } > $@.tmp && $(commit)
define m3_group
$(M3)/tx_$(1).rad: $(OUT)/scene/win.rad $(M3)/preflight.ok
	{ echo "#@rfluxmtx h=kf u=$(call hd_ux,$(UP_$(1)))"; echo "void glow $(1)_tx 0 0 4 1 1 1 0"; \
	  $(SPLIT) -v mode=sel -v mod=$(MOD_$(1)) -v newmod=$(1)_tx -v name=win.rad $(OUT)/scene/win.rad; } > $$@.tmp && mv -f $$@.tmp $$@
# D with the exterior ground as geometry: the sun in the sky vector lights it, with its shadows
$(M3)/d_$(1).mtx: $(M3)/tx_$(1).rad $(M3)/sky_rx.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad
	$(STAGE) 3pm_rfluxmtx_D_$(1) rfluxmtx -n $(NPROC) $(D3_OPTS) $(M3)/tx_$(1).rad $(M3)/sky_rx.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad > $$@.tmp
	mv -f $$@.tmp $$@
$(M3)/td_$(1).mtx: $(M3)/d_$(1).mtx $(call hd_klems,$(1))
	rmtxop $(call hd_klems,$(1)) $(M3)/d_$(1).mtx > $$@.tmp && mv -f $$@.tmp $$@
endef
define m3_view
$(1)_3PM = pmcompose -n $(NPROC) -c $(SHADE_LIMIT) -w $(WEATHER) -vf $(2) -ms $(SKYMF) -sunsky \
  $(foreach g,$(GROUPS),-V $(OUT)/$(1)/v/$(g)/%03d.hdr $(M3)/td_$(g).mtx)
$(M3)/$(1)/annual.done: $(OUT)/$(1)/v $(foreach g,$(GROUPS),$(M3)/td_$(g).mtx)
	mkdir -p $(M3)/$(1)
	$(if $(HOURLY_OPT),rm -rf $(M3)/$(1)/hourly.tmp && mkdir -p $(M3)/$(1)/hourly.tmp)
	$(STAGE) 3pm_pmcompose_$(1) $$($(1)_3PM) -t -o $(M3)/$(1)/annual.csv -S $(M3)/$(1)/summary.txt -L $(M3)/$(1)/hours.log \
	  $(if $(HOURLY_OPT),-I $(M3)/$(1)/hourly.tmp/h%04d.$(IMAGEFMT) $(if $(filter exr,$(IMAGEFMT)),-e))
	$(if $(HOURLY_OPT),rm -rf $(M3)/$(1)/hourly && mv $(M3)/$(1)/hourly.tmp $(M3)/$(1)/hourly)
	touch $$@
$(M3)/$(1)/selected.done: $(M3)/$(1)/annual.done
	rm -rf $(M3)/$(1)/selected.tmp && mkdir -p $(M3)/$(1)/selected.tmp
	$$($(1)_3PM) -r $$$$(cbdmreport -n $(NSELECT) -select $(M3)/$(1)/hours.log) -I $(M3)/$(1)/selected.tmp/h%04d.hdr -o /dev/null
	rm -rf $(M3)/$(1)/selected && mv $(M3)/$(1)/selected.tmp $(M3)/$(1)/selected
	touch $$@
endef
$(M3)/params.txt: $(M3)/preflight.ok
	{ echo "method = plain three-phase with the sun (V T D s; sky vectors with the sun in their patches)"; \
	  echo "weather = $(WEATHER)"; echo "window groups = $(foreach g,$(GROUPS),$(g): $(MAT_$(g)), Klems $(KLEMS_$(g));)"; \
	  echo "glare views = $(GLARE_VIEWS)"; echo "resolution = $(RES) x $(RES)"; echo "sky = Reinhart MF:$(SKYMF) (sun shared among its 4 nearest patches)"; \
	  echo "V options = $(V_OPTS)"; echo "D options = $(D3_OPTS)"; echo "threads = $(NPROC)"; } > $@.tmp && $(commit)

# ================================================================= imageless (dcglare)
MI = $(OUT)/imageless
MI_RC = rcontrib -I+ -n $(NPROC) -f reinhart.cal -p MF=$(SKYMF) -b rbin -bn Nrbins -m skyglow
$(MI)/sky.smx: $(OUT)/preflight.ok
	mkdir -p $(MI)
	gendaymtx -m $(SKYMF) -of $(WEATHER) > $@.tmp 2> $(MI)/gendaymtx.log && $(commit)
# every weather record (record month day hour DNI DHI) and the site (gendaylit's latitude, longitude,
# meridian): pipeline/weather.awk; the imageless method and the backward reference (reference.mk)
$(OUT)/records.txt $(OUT)/site.txt &: $(OUT)/preflight.ok $(HELIODON_PIPE)/weather.awk
	awk -v site=$(OUT)/site.txt.tmp -f $(HELIODON_PIPE)/weather.awk $(WEATHER) > $(OUT)/records.txt.tmp
	mv -f $(OUT)/site.txt.tmp $(OUT)/site.txt && mv -f $(OUT)/records.txt.tmp $(OUT)/records.txt
define mi_view
$(MI)/$(1)/eye.txt: $(2) $(OUT)/preflight.ok
	mkdir -p $(MI)/$(1)
	awk '{for (i = 1; i < NF; i++) {if ($$$$i == "-vp") {p = $$$$(i+1) " " $$$$(i+2) " " $$$$(i+3)} if ($$$$i == "-vd") {d = $$$$(i+1) " " $$$$(i+2) " " $$$$(i+3)} if ($$$$i == "-vu") {u = $$$$(i+1) " " $$$$(i+2) " " $$$$(i+3)}}} \
	  END {if (p == "" || d == "") exit 1; print p, d; print (u == "" ? "0 0 1" : u) > "$(MI)/$(1)/up.txt"}' $(2) > $$@.tmp && mv -f $$@.tmp $$@
$(MI)/$(1)/dc_direct.mtx: $(OUT)/skyg.oct $(MI)/$(1)/eye.txt
	$(STAGE) imageless_direct_$(1) sh -c '$(MI_RC) $(IMGL_DIRECT_OPTS) $(OUT)/skyg.oct < $(MI)/$(1)/eye.txt > $$@.tmp'
	mv -f $$@.tmp $$@
$(MI)/$(1)/dc_total.mtx: $(OUT)/skyg.oct $(MI)/$(1)/eye.txt
	$(STAGE) imageless_total_$(1) sh -c '$(MI_RC) $(IMGL_OPTS) $(OUT)/skyg.oct < $(MI)/$(1)/eye.txt > $$@.tmp'
	mv -f $$@.tmp $$@
# annual.csv: record,month,day,hour,Ev,DGP for every record with light at the eye
$(MI)/$(1)/annual.csv: $(MI)/$(1)/dc_direct.mtx $(MI)/$(1)/dc_total.mtx $(MI)/sky.smx $(OUT)/records.txt
	$(STAGE) imageless_dcglare_$(1) sh -c 'dcglare -h -b $(IMGL_B) -vf $(MI)/$(1)/eye.txt -vu $$$$(cat $(MI)/$(1)/up.txt) $(MI)/$(1)/dc_direct.mtx $(MI)/$(1)/dc_total.mtx $(MI)/sky.smx > $(MI)/$(1)/dgp.txt'
	dctimestep -oa $(MI)/$(1)/dc_total.mtx $(MI)/sky.smx | awk 'data {for (i = 1; i + 2 <= NF; i += 3) \
	  printf "%.2f\n", 179 * (0.265074126 * $$$$i + 0.670114631 * $$$$(i+1) + 0.064811243 * $$$$(i+2))} !NF {data = 1}' > $(MI)/$(1)/ev.txt
	{ echo "record,month,day,hour,Ev,DGP"; tr '\t' '\n' < $(MI)/$(1)/dgp.txt | awk 'NF' | paste -d' ' <(cut -d' ' -f1-4 $(OUT)/records.txt) $(MI)/$(1)/ev.txt - | \
	  awk '$$$$5 > 0 {printf "%d,%d,%d,%.3f,%.2f,%.4f\n", $$$$1, $$$$2, $$$$3, $$$$4, $$$$5, $$$$6}'; } > $$@.tmp && mv -f $$@.tmp $$@
$(MI)/$(1)/summary.txt: $(MI)/$(1)/annual.csv
	tail -n +2 $$< | cut -d, -f6 | sort -g | awk '{d[NR] = $$$$1} END {k = 0.95 * (NR - 1) + 1; i = int(k); f = k - i; \
	  printf "hours %d\nDGP_p95 %.4f\n", NR, (i < NR ? d[i] + f * (d[i+1] - d[i]) : d[NR])}' > $$@.tmp && mv -f $$@.tmp $$@
endef
$(MI)/params.txt: $(OUT)/preflight.ok
	mkdir -p $(MI)
	{ echo "method = imageless DGP (dcglare semantics), eye point and direction of each glare view"; echo "weather = $(WEATHER)"; \
	  echo "sky = Reinhart MF:$(SKYMF), gendaymtx with the sun in its patches"; echo "direct DC options = $(IMGL_DIRECT_OPTS)"; \
	  echo "total DC options = $(IMGL_OPTS)"; echo "glare-source threshold = $(IMGL_B)"; } > $@.tmp && $(commit)

# the report of an image method's folder $(1) (3pm, 5pm) labelled $(2): cbdmreport per glare view
define hd_method_report
method: $(1)/report/index.html
$(1)/report/index.html: $(foreach v,$(HD_GLARE),$(1)/$(v)/selected.done) $(1)/params.txt $(HELIODON_PIPE)/report.sh
	rm -rf $(1)/report.tmp && mkdir -p $(1)/report.tmp
	touch $(OUT)/timings.txt
	$(foreach v,$(HD_GLARE),cat $(1)/$(v)/summary.txt $(NOTES) > $(1)/$(v)/notes.txt && \
	  cbdmreport -c $(1)/$(v)/annual.csv -o $(1)/report.tmp/$(v) -s $(SHADE_LIMIT) -p $(1)/params.txt -T $(OUT)/timings.txt \
	  -N $(1)/$(v)/notes.txt -title "$(TITLE) ($(2)), view $(v)" $(1)/$(v)/selected/*.hdr;)
	$(HELIODON_PIPE)/report.sh $(1) $(1)/report.tmp "$(TITLE) ($(2))" "$(HD_GLARE)" "$(HD_GLARE)" "" $(1) $(1)/params.txt > $(1)/report.tmp/index.html
	rm -rf $(1)/report && mv $(1)/report.tmp $(1)/report
endef
# ================================================================= the five-phase method
include $(HELIODON_PIPE)/fivephase.mk

# ================================================================= comparison of the methods present
# OUT/compare/VIEW.csv: record,month,day,hour and the DGP of pm, 3pm, imageless, 5pm (empty when a
# method has no result for the hour); VIEW_dgi.csv the same columns with the DGI of the image methods
# (imageless has none); OUT/compare/VIEW.txt: per method pair the hours in common, mean and largest
# |dDGP| (with its record), and each method's 95th percentile over the common hours.
define cmp_view
$(1)_CMP_IN = $(wildcard $(OUT)/$(1)/hours.log $(M3)/$(1)/hours.log $(MI)/$(1)/annual.csv $(M5)/$(1)/hours.log)
$(OUT)/compare/$(1).csv: hd_force $$($(1)_CMP_IN) $(HELIODON_PIPE)/methods.mk
	mkdir -p $(OUT)/compare
	{ echo "record,month,day,hour,pm,3pm,imageless,5pm"; awk 'FILENAME ~ /annual.csv$$$$/ {if (FNR > 1) {split($$$$0, a, ","); k[a[1]] = a[2] "," a[3] "," a[4]; im[a[1]] = a[6]} next} \
	  /^#/ {next} {k[$$$$1] = $$$$2 "," $$$$3 "," $$$$4; if (FILENAME ~ /\/3pm\//) t[$$$$1] = $$$$NF; else if (FILENAME ~ /\/5pm\//) f[$$$$1] = $$$$NF; else p[$$$$1] = $$$$NF} \
	  END {for (r in k) printf "%d,%s,%s,%s,%s,%s\n", r, k[r], p[r], t[r], im[r], f[r]}' \
	  $$($(1)_CMP_IN) | sort -t, -k1,1n; } > $$@.tmp
	mv -f $$@.tmp $$@
# DGI per record: the hour log and the glare CSV of a method list the same hours in the same order
$(OUT)/compare/$(1)_dgi.csv: $(OUT)/compare/$(1).csv
	{ echo "record,month,day,hour,pm,3pm,imageless,5pm"; for m in pm 3pm 5pm; do d=$(OUT)/$$$$m; [ $$$$m = pm ] && d=$(OUT); \
	  [ -s $$$$d/$(1)/hours.log ] && [ -s $$$$d/$(1)/annual.csv ] || continue; \
	  paste -d' ' <(grep -v '^#' $$$$d/$(1)/hours.log | awk '{print $$$$1, $$$$2, $$$$3, $$$$4}') <(tail -n +2 $$$$d/$(1)/annual.csv | cut -d, -f4) | sed "s/^/$$$$m /"; done | \
	  awk '{k[$$$$2] = $$$$3 "," $$$$4 "," $$$$5; v[$$$$1, $$$$2] = $$$$6} END {for (r in k) printf "%d,%s,%s,%s,,%s\n", r, k[r], v["pm", r], v["3pm", r], v["5pm", r]}' | sort -t, -k1,1n; } > $$@.tmp
	mv -f $$@.tmp $$@
$(OUT)/compare/$(1).txt: $(OUT)/compare/$(1).csv $(HELIODON_PIPE)/compare.sh
	$(HELIODON_PIPE)/compare.sh $$< > $$@.tmp && mv -f $$@.tmp $$@
endef

ifneq ($(HD_TOP2),1)
$(foreach g,$(GROUPS),$(eval $(call m3_group,$(g))))
$(foreach v,$(HD_GLARE),$(eval $(call m3_view,$(v),$(call hd_vfile,$(v)))))
$(foreach v,$(HD_GLARE),$(eval $(call mi_view,$(v),$(call hd_vfile,$(v)))))
$(foreach v,$(HD_GLARE),$(eval $(call cmp_view,$(v))))
compare: $(foreach v,$(HD_GLARE),$(OUT)/compare/$(v).txt) $(OUT)/compare/index.html
	@cat $(foreach v,$(HD_GLARE),$(OUT)/compare/$(v).txt)
$(OUT)/compare/index.html: $(foreach v,$(HD_GLARE),$(OUT)/compare/$(v).csv $(OUT)/compare/$(v)_dgi.csv) $(HELIODON_PIPE)/compare_html.sh \
  $(foreach v,$(HD_GLARE),$(if $(filter reference,$(MAKECMDGOALS)),$(OUT)/compare/$(v)_ref/table.csv,$(wildcard $(OUT)/compare/$(v)_ref/table.csv)))
	$(HELIODON_PIPE)/compare_html.sh "$(TITLE)" $(OUT)/timings.txt $(foreach v,$(HD_GLARE),$(OUT)/compare/$(v).csv) > $@.tmp && $(commit)
endif

include $(HELIODON_PIPE)/reference.mk

# ---- the METHOD's report: cbdmreport per glare view (3pm), the summary and comparison (imageless)
ifeq ($(METHOD),3pm)
$(eval $(call hd_method_report,$(M3),plain 3PM))
endif
ifeq ($(METHOD),imageless)
method: $(MI)/index.html
$(MI)/index.html: $(foreach v,$(HD_GLARE),$(MI)/$(v)/summary.txt) $(MI)/params.txt
	{ echo "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>$(TITLE) (imageless DGP)</title></head><body>"; \
	  echo "<h1>$(TITLE): imageless DGP</h1><h2>Run</h2><pre>"; cat $(MI)/params.txt; echo "</pre>"; \
	  $(foreach v,$(HD_GLARE),echo "<h2>View $(v)</h2><pre>"; cat $(MI)/$(v)/summary.txt; echo "</pre><p>Hourly: <code>$(v)/annual.csv</code></p>";) \
	  echo "</body></html>"; } > $@.tmp && $(commit)
endif

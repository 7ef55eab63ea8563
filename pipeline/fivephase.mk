# heliodon pipeline: METHOD=5pm, the five-phase method (included by methods.mk; heliodon-pipeline(7)).
#
# The steps of the recipe Radiance users run (the paper's Appendix A), with heliodon's tools; every
# intermediate stays under OUT/5pm/:
#   1. the 3PM series: V (OUT/VIEW/v, shared) T D s with the sun in the sky vectors (METHOD=3pm's
#      T*D matrices, OUT/3pm/td_<group>.mtx): I_3PM;
#   2. the view's reflectance map: rpict -ab 0 -av 1/pi of the scene with the window groups as glows of
#      1 (map_a.hdr: rho/pi on the room's surfaces, 1 on the window pixels) and of the same scene with
#      every other material black (map_b.hdr: the window pixels only); pcomb map_a - map_b = map.hdr;
#   3. the black-interior view matrix of one bounce: vwrays | rfluxmtx -i -ab 1 on the black scene
#      (VIEW/vd/<group>/%03d.hdr: irradiance on the surfaces seen, the Klems patch itself on the window
#      pixels), times map_a (pcomb, VIEW/vdr/), and the direct daylight matrices (rfluxmtx -ab 0 on the
#      black scene, dd_<group>.mtx; T*Dd = tdd_<group>.mtx): I_sun,3PM with the sun-only sky vector
#      (gendaymtx -d) is the 3PM's direct sun on the room's surfaces and seen through the windows;
#   4. the direct-sun coefficients of Reinhart MF:FIVE_MF (gensuns -m 6: suns.rad, mods.txt) on the
#      black scene with the window materials: rcontrib -i -ab 1 (VIEW/cdsi/solarN.hdr) times map.hdr,
#      plus the fenestration DC of the visible windows (rcontrib without -i on the window pixels of the
#      mask, VIEW/cdsl/: the sun seen through them); pcomb cdsi * map + cdsl = VIEW/cds/solarN.hdr;
#      with FIVE_OS = k > 1 the pixels of this step are oversampled: cdsi, cdsl and a second map pair
#      (VIEW/os/) at k RES, the products box-filtered to RES (pfilt -1), the paper's remedy for thin
#      sunlit strips that one ray per pixel hits or misses;
#   5. I_5PM = I_3PM - I_sun,3PM + I_sun,5185: pmcompose -sunsky -V ... -Vd ... -s cds/solar%d.hdr -m 6,
#      into the same glare evaluation, hour log, selected hours and report as the other methods.
# The selected hours keep their three parts (VIEW/parts/: 3pm_, 3pm-sun3pm_, sun5185_ hNNNN.hdr).

M5 = $(OUT)/5pm
FIVE_MF       ?= 6
FIVE_VD_OPTS  ?= -ab 1 -ad 1024 -lw 1e-4
FIVE_DD_OPTS  ?= -c 200 -ab 0
FIVE_CDS_OPTS ?= -ab 1 -ad 256 -lw 1e-3 -dc 1 -dt 0 -dj 0
FIVE_FEN_OPTS ?= -ab 0 -dj 0
FIVE_OS       ?= 1
# step 4 for these MF:FIVE_MF sun patches only (empty: every patch the weather needs): a check of
# single hours at a high FIVE_OS in its own OUT; the year's composition then lacks the other suns
FIVE_SUNS     ?=
M5_ORES       = $(shell echo $$(( $(RES) * $(FIVE_OS) )))
FIVE_AV       := 0.3183099 0.3183099 0.3183099
# pcomb products of two and three pictures, per channel (files: the loops run under sh -c)
ifeq ($(METHOD),5pm)
$(if $(filter $(FIVE_OS),1 2 3 4 5 6 7 8),,$(error heliodon-pipeline: METHOD=5pm: FIVE_OS='$(FIVE_OS)': expected an oversampling factor 1..8))
$(if $(filter-out 1,$(words $(FIVE_MF))),$(error heliodon-pipeline: METHOD=5pm: FIVE_MF='$(FIVE_MF)': expected a Reinhart subdivision 1..10))
$(if $(filter $(FIVE_MF),1 2 3 4 5 6 7 8 9 10),,$(error heliodon-pipeline: METHOD=5pm: FIVE_MF='$(FIVE_MF)': expected a Reinhart subdivision 1..10))
endif
M5_MUL  = -f $(M5)/mul.cal
M5_MAD  = -f $(M5)/mad.cal

$(M5)/preflight.ok: $(M3)/preflight.ok
	@mkdir -p $(M5)
	@echo 'ro=ri(1)*ri(2);go=gi(1)*gi(2);bo=bi(1)*bi(2);' > $(M5)/mul.cal
	@echo 'ro=ri(1)*ri(2)+ri(3);go=gi(1)*gi(2)+gi(3);bo=bi(1)*bi(2)+bi(3);' > $(M5)/mad.cal
	@touch $@
# the black scene: every surface but the window groups' takes the material black
$(M5)/black.rad: $(OUT)/scene/room.rad $(OUT)/scene/ground.rad $(M5)/preflight.ok
	{ echo "void plastic black 0 0 5 0 0 0 0 0"; xform -m black $(OUT)/scene/room.rad $(OUT)/scene/ground.rad; } > $@.tmp && $(commit)
# step 4's suns and their octree (window materials, black scene)
$(M5)/suns.rad $(M5)/mods.txt &: $(M5)/preflight.ok
	$(STAGE) 5pm_gensuns gensuns -m $(FIVE_MF) -M $(M5)/mods.txt.tmp -o $(M5)/suns.rad.tmp $(WEATHER)
	$(if $(strip $(FIVE_SUNS)),awk -v l='$(strip $(FIVE_SUNS))' 'BEGIN {n = split(l, p, " "); for (i = 1; i <= n; i++) k["solar" p[i]] = 1} \
	  FNR == 1 {f++} f == 1 {if ($$1 in k) {print > "$(M5)/mods.txt.tmp2"; m++}; next} \
	  /^void light solar/ {on = ($$3 in k)} /^solar[0-9]+ source/ {on = ($$1 in k)} /^#/ || on {print > "$(M5)/suns.rad.tmp2"} \
	  END {if (m != n) {print "heliodon-pipeline: FIVE_SUNS=" l ": " m " of " n " patches are suns of the weather" > "/dev/stderr"; exit 1}}' \
	  $(M5)/mods.txt.tmp $(M5)/suns.rad.tmp && mv -f $(M5)/mods.txt.tmp2 $(M5)/mods.txt.tmp && mv -f $(M5)/suns.rad.tmp2 $(M5)/suns.rad.tmp)
	mv -f $(M5)/mods.txt.tmp $(M5)/mods.txt && mv -f $(M5)/suns.rad.tmp $(M5)/suns.rad
$(M5)/sun.oct: $(OUT)/mat.rad $(M5)/black.rad $(OUT)/scene/win.rad $(M5)/suns.rad
	oconv $(OUT)/mat.rad $(M5)/black.rad $(OUT)/scene/win.rad $(M5)/suns.rad > $@.tmp && $(commit)
# step 2's pair: windows as glows of 1 with the room's materials (mask.oct) or black ones
$(M5)/mapb.oct: $(OUT)/scene/mask.rad $(M5)/black.rad $(OUT)/scene/win.rad
	oconv $(OUT)/scene/mask.rad $(M5)/black.rad $(OUT)/scene/win.rad > $@.tmp && $(commit)

define m5_group
# step 3: the direct daylight matrix (-ab 0 on the black scene) and T*Dd
$(M5)/dd_$(1).mtx: $(M3)/tx_$(1).rad $(M3)/sky_rx.rad $(M5)/black.rad
	$(STAGE) 5pm_rfluxmtx_Dd_$(1) rfluxmtx -n $(NPROC) $(FIVE_DD_OPTS) $(M3)/tx_$(1).rad $(M3)/sky_rx.rad $(M5)/black.rad > $$@.tmp
	mv -f $$@.tmp $$@
$(M5)/tdd_$(1).mtx: $(M5)/dd_$(1).mtx $(call hd_klems,$(1))
	rmtxop $(call hd_klems,$(1)) $(M5)/dd_$(1).mtx > $$@.tmp && mv -f $$@.tmp $$@
endef

# m5_map DIR VIEWFILE RES: step 2's pair at that resolution (map_b is the window mask)
define m5_map
$(1)/map.hdr: $(OUT)/mask.oct $(M5)/mapb.oct $(2) $(M5)/preflight.ok
	mkdir -p $(1)
	rpict -vf $(2) -x $(3) -y $(3) -ps 1 -pj 0 -dj 0 -ab 0 -av $(FIVE_AV) $(OUT)/mask.oct > $(1)/map_a.hdr.tmp
	rpict -vf $(2) -x $(3) -y $(3) -ps 1 -pj 0 -dj 0 -ab 0 -av $(FIVE_AV) $(M5)/mapb.oct > $(1)/map_b.hdr.tmp
	mv -f $(1)/map_a.hdr.tmp $(1)/map_a.hdr && mv -f $(1)/map_b.hdr.tmp $(1)/map_b.hdr
	pcomb -e 'ro=ri(1)-ri(2);go=gi(1)-gi(2);bo=bi(1)-bi(2)' -o $(1)/map_a.hdr -o $(1)/map_b.hdr > $$@.tmp && mv -f $$@.tmp $$@
endef

define m5_view
$(1)_5VW = -vf $(2) -x $(RES) -y $(RES)
$$(eval $$(call m5_map,$(M5)/$(1),$(2),$(RES)))
ifneq ($(FIVE_OS),1)
$$(eval $$(call m5_map,$(M5)/$(1)/os,$(2),$(M5_ORES)))
$(1)_5OS = $(M5)/$(1)/os
$(1)_5MASK = $(M5)/$(1)/os/map_b.hdr
else
$(1)_5OS = $(M5)/$(1)
$(1)_5MASK = $(OUT)/$(1)/mask.hdr
endif
$(1)_5VWO = -vf $(2) -x $(M5_ORES) -y $(M5_ORES)
# step 3: black-interior view matrix, irradiance, one bounce; then times map_a
$(M5)/$(1)/rx_vd.rad: $(OUT)/$(1)/rx_all.rad $(M5)/preflight.ok
	mkdir -p $(M5)/$(1)
	sed 's|o=$(OUT)/$(1)/v.tmp/|o=$(M5)/$(1)/vd.tmp/|' $(OUT)/$(1)/rx_all.rad > $$@.tmp && mv -f $$@.tmp $$@
$(M5)/$(1)/vd: $(M5)/$(1)/rx_vd.rad $(M5)/black.rad
	rm -rf $$@.tmp && mkdir -p $(foreach g,$(GROUPS),$$@.tmp/$(g))
	$(STAGE) 5pm_rfluxmtx_Vd_$(1) sh -c 'vwrays -ff $$($(1)_5VW) | rfluxmtx -ffc $$$$(vwrays -d $$($(1)_5VW)) -n $(NPROC) -i $(FIVE_VD_OPTS) - $(M5)/$(1)/rx_vd.rad $(M5)/black.rad'
	rm -rf $$@ && mv $$@.tmp $$@
$(M5)/$(1)/vdr: $(M5)/$(1)/vd $(M5)/$(1)/map.hdr
	rm -rf $$@.tmp && mkdir -p $(foreach g,$(GROUPS),$$@.tmp/$(g))
	$(STAGE) 5pm_pcomb_Vd_$(1) sh -c 'for f in $(foreach g,$(GROUPS),$(M5)/$(1)/vd/$(g)/*.hdr); do \
	  g=$$$${f%/*}; g=$$$${g##*/}; pcomb $(M5_MUL) -o $(M5)/$(1)/map_a.hdr -o $$$$f > $$@.tmp/$$$$g/$$$${f##*/} || exit 1; done'
	rm -rf $$@ && mv $$@.tmp $$@
# step 4: sun coefficients (irradiance x map) and the fenestration DC of the window pixels
$(M5)/$(1)/cdsi: $(M5)/sun.oct $(M5)/mods.txt $(2)
	rm -rf $$@.tmp && mkdir -p $$@.tmp
	$(STAGE) 5pm_rcontrib_sun_$(1) sh -c 'vwrays -ff $$($(1)_5VWO) | rcontrib -ffc $$$$(vwrays -d $$($(1)_5VWO)) -n $(NPROC) -i $(FIVE_CDS_OPTS) -o $$@.tmp/%s.hdr -M $(M5)/mods.txt $(M5)/sun.oct'
	rm -rf $$@ && mv $$@.tmp $$@
$(M5)/$(1)/cdsl: $(M5)/sun.oct $(M5)/mods.txt $(OUT)/$(1)/mask.hdr $$($(1)_5OS)/map.hdr $(2)
	rm -rf $$@.tmp && mkdir -p $$@.tmp
	$(STAGE) 5pm_rcontrib_fen_$(1) sh -c 'vwrays -ff $$($(1)_5VWO) | pmmask -t $$($(1)_5MASK) | rcontrib -ffc $$$$(vwrays -d $$($(1)_5VWO)) -n $(NPROC) $(FIVE_FEN_OPTS) -o $$@.tmp/%s.hdr -M $(M5)/mods.txt $(M5)/sun.oct'
	rm -rf $$@ && mv $$@.tmp $$@
$(M5)/$(1)/cds: $(M5)/$(1)/cdsi $(M5)/$(1)/cdsl $$($(1)_5OS)/map.hdr
	rm -rf $$@.tmp && mkdir -p $$@.tmp
	$(STAGE) 5pm_pcomb_sun_$(1) sh -c 'for f in $(M5)/$(1)/cdsi/*.hdr; do b=$$$${f##*/}; \
	  pcomb $(M5_MAD) -o $$($(1)_5OS)/map.hdr -o $$$$f -o $(M5)/$(1)/cdsl/$$$$b $(if $(filter-out 1,$(FIVE_OS)),| pfilt -1 -x $(RES) -y $(RES)) > $$@.tmp/$$$$b || exit 1; done'
	rm -rf $$@ && mv $$@.tmp $$@
# step 5: the composition (and its parts for the selected hours)
$(1)_5PM_3 = pmcompose -n $(NPROC) -w $(WEATHER) -vf $(2) -ms $(SKYMF) -sunsky $(foreach g,$(GROUPS),-V $(OUT)/$(1)/v/$(g)/%03d.hdr $(M3)/td_$(g).mtx)
$(1)_5PM_D = $(foreach g,$(GROUPS),-Vd $(M5)/$(1)/vdr/$(g)/%03d.hdr $(M5)/tdd_$(g).mtx)
$(1)_5PM_S = -m $(FIVE_MF) -s $(M5)/$(1)/cds/solar%d.hdr
$(1)_5PM = $$($(1)_5PM_3) $$($(1)_5PM_D) $$($(1)_5PM_S) -c $(SHADE_LIMIT)
$(1)_5PM_DEPS = $(OUT)/$(1)/v $(M5)/$(1)/vdr $(M5)/$(1)/cds $(foreach g,$(GROUPS),$(M3)/td_$(g).mtx $(M5)/tdd_$(g).mtx)
$(M5)/$(1)/annual.done: $$($(1)_5PM_DEPS)
	$(if $(HOURLY_OPT),rm -rf $(M5)/$(1)/hourly.tmp && mkdir -p $(M5)/$(1)/hourly.tmp)
	$(STAGE) 5pm_pmcompose_$(1) $$($(1)_5PM) -t -o $(M5)/$(1)/annual.csv -S $(M5)/$(1)/summary.txt -L $(M5)/$(1)/hours.log \
	  $(if $(HOURLY_OPT),-I $(M5)/$(1)/hourly.tmp/h%04d.$(IMAGEFMT) $(if $(filter exr,$(IMAGEFMT)),-e))
	$(if $(HOURLY_OPT),rm -rf $(M5)/$(1)/hourly && mv $(M5)/$(1)/hourly.tmp $(M5)/$(1)/hourly)
	touch $$@
$(M5)/$(1)/selected.done: $(M5)/$(1)/annual.done
	rm -rf $(M5)/$(1)/selected.tmp $(M5)/$(1)/parts.tmp && mkdir -p $(M5)/$(1)/selected.tmp $(M5)/$(1)/parts.tmp
	r=$$$$(cbdmreport -n $(NSELECT) -select $(M5)/$(1)/hours.log) && \
	$$($(1)_5PM) -r $$$$r -I $(M5)/$(1)/selected.tmp/h%04d.hdr -o /dev/null && \
	$$($(1)_5PM_3) -noglare -r $$$$r -I $(M5)/$(1)/parts.tmp/3pm_h%04d.hdr && \
	$$($(1)_5PM_3) $$($(1)_5PM_D) -noglare -r $$$$r -I $(M5)/$(1)/parts.tmp/3pm-sun3pm_h%04d.hdr && \
	pmcompose -n $(NPROC) -w $(WEATHER) -vf $(2) $$($(1)_5PM_S) -noglare -r $$$$r -I $(M5)/$(1)/parts.tmp/sun5185_h%04d.hdr
	rm -rf $(M5)/$(1)/selected $(M5)/$(1)/parts && mv $(M5)/$(1)/selected.tmp $(M5)/$(1)/selected && mv $(M5)/$(1)/parts.tmp $(M5)/$(1)/parts
	touch $$@
endef

$(M5)/params.txt: $(M5)/preflight.ok
	{ echo "method = five-phase (I_3PM - I_sun,3PM + I_sun,MF:$(FIVE_MF); the paper's Appendix A)"; \
	  echo "weather = $(WEATHER)"; echo "window groups = $(foreach g,$(GROUPS),$(g): $(MAT_$(g)), Klems $(KLEMS_$(g));)"; \
	  echo "glare views = $(GLARE_VIEWS)"; echo "resolution = $(RES) x $(RES)"; \
	  echo "sky = Reinhart MF:$(SKYMF) (3PM: the sun shared among its 4 nearest patches)"; echo "sun patches = Reinhart MF:$(FIVE_MF)"; \
	  echo "V options = $(V_OPTS)"; echo "D options = $(D3_OPTS)"; echo "black-interior V options = -i $(FIVE_VD_OPTS)"; \
	  echo "direct D options = $(FIVE_DD_OPTS)"; echo "sun coefficient options = -i $(FIVE_CDS_OPTS)"; \
	  echo "sun coefficient oversampling = $(FIVE_OS) x $(FIVE_OS) per pixel"; $(if $(strip $(FIVE_SUNS)),echo "sun patches computed = $(strip $(FIVE_SUNS)) only";) echo "window pixels' sun options = $(FIVE_FEN_OPTS)"; echo "threads = $(NPROC)"; } > $@.tmp && $(commit)

ifneq ($(HD_TOP2),1)
$(foreach g,$(GROUPS),$(eval $(call m5_group,$(g))))
$(foreach v,$(HD_GLARE),$(eval $(call m5_view,$(v),$(call hd_vfile,$(v)))))
endif

ifeq ($(METHOD),5pm)
$(eval $(call hd_method_report,$(M5),5PM))
endif

# heliodon annual PM-CBDM pipeline (Grobe 2019): include this file from a short case Makefile
# that sets the case's variables (heliodon-pipeline(7) lists them all with their defaults):
#
#   SCENE   = room.rad site.rad          # room and surroundings, without the window groups
#   GROUPS  = south skylight             # window groups, any names
#   GEOM_south = windows.rad             # file holding the group's surfaces (may be shared)
#   MOD_south  = south_win               # their modifier in that file (default: the group name)
#   MAT_south  = glass | file.xml | file.rad   (+ UP_south, KLEMS_south, CLOSED_south)
#   VIEWS   = v1.vf v2.vf   SENSORS = grid.pts   WEATHER = site.epw
#   include $(shell heliodon-config --pipeline)   # or the path of this file
#
# Stages are make targets on their final file names; every output is written under a temporary
# name and renamed, so a killed run started again continues from its finished stages.
# Run "make preflight" to check the inputs only.

HELIODON_PIPE := $(abspath $(dir $(lastword $(MAKEFILE_LIST))))

# ---------------------------------------------------------------- case variables
SCENE       ?=
GROUPS      ?=
VIEWS       ?=
SENSORS     ?=
WEATHER     ?=
GROUND_MOD  ?=
OUT         ?= run
RES         ?= 64
MF          ?= 1
SKYMF       ?= 1
PHOTONS     ?= 200k
PM_SEED     ?= 0
SUN_UNIT    ?= 0
# record pieces per DC folder: 1 on one machine; with SUBMIT=slurm one per 256k pixels of a view
DC_PIECES   ?= $(if $(filter slurm,$(SUBMIT)),$(shell echo $$(( ($(RES) * $(RES) + 262143) / 262144 ))),1)
# hour pieces of each view's composition: 1 on one machine, as DC_PIECES with SUBMIT=slurm
HOUR_PIECES ?= $(if $(filter slurm,$(SUBMIT)),$(DC_PIECES),1)
BANDWIDTH   ?= 50
NPROC       ?= 2
BSDFPATH    ?=
GLARE_VIEWS ?= $(HD_FISHEYE_VIEWS)
SHADE_LIMIT ?= 0.40
SUNMETHOD   ?= pm
SUN_OPTS    ?= -ab -1
SUN_BACKWARD_OPTS ?= -ab 3 -ad 256 -lw 1e-4 -dn 4
SKY_OPTS    ?= -ab 3 -ad 256 -lw 1e-4
FEN_OPTS    ?= -ab 3 -ad 1024 -lw 1e-4
FENSUN_OPTS ?= -ab 2 -ad 128 -lw 1e-4 -dn 4
FENSUN_C    ?= 4
FENSUN_PJ   ?= 0
FENSUN      ?= 1
SUN         ?= 1
FEN         ?= 1
SKYMETHOD   ?= dc
V_OPTS      ?= -ab 3 -ad 256 -lw 1e-4
D_OPTS      ?= -c 200 -ab 2 -ad 256 -lw 1e-4
GROUNDSUN   ?= sky
GROUNDPTS   ?= 1024
GROUNDPTS_CMD ?=
SENSOR_SUNMETHOD ?= backward
SENSOR_SUN_OPTS ?= $(if $(filter pm,$(SENSOR_SUNMETHOD)),-ab 1 -ad 256 -lw 1e-4,-ab 3 -ad 1024 -lw 1e-4 -dn 16)
SENSOR_SKY_OPTS ?= -ab 3 -ad 1024 -lw 1e-4
DA_LUX      ?= 300
SDA_FRAC    ?= 0.5
ASE_LUX     ?= 1000
ASE_HOURS   ?= 250
UDI_BANDS   ?= 100 300 3000
OCC_HOURS   ?= 8 18
IMAGES      ?= 0
IMAGEFMT    ?= hdr
KEEPALL     ?= 0
NSELECT     ?= 3
NOTES       ?=
TITLE       ?= Annual daylight and glare (PM-CBDM)
STATE       ?= open

comma := ,
space := $(eval) $(eval)
SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -c
.DELETE_ON_ERROR:
.SUFFIXES:

# ---------------------------------------------------------------- derived names
hd_uniq = $(if $1,$(firstword $1) $(call hd_uniq,$(filter-out $(firstword $1),$1)))
hd_vname = $(basename $(notdir $1))
# group names become make and environment variable names: checked before anything else
HD_BADNAMES := $(shell printf '%s\n' $(GROUPS) | grep -v '^[A-Za-z_][A-Za-z0-9_]*$$')
$(if $(HD_BADNAMES),$(error heliodon-pipeline: GROUPS: '$(firstword $(HD_BADNAMES))' is not a valid group name (letters, digits, _)))
$(foreach g,$(GROUPS),$(if $(filter-out 1,$(words $(filter $(g),$(GROUPS)))),$(error heliodon-pipeline: GROUPS: group '$(g)' is named twice)))
$(foreach g,$(GROUPS),$(eval MOD_$(g) ?= $(g))$(eval UP_$(g) ?= 0 0 1))
ifeq ($(STATE),closed)
$(foreach g,$(GROUPS),$(if $(CLOSED_$(g)),$(eval MAT_$(g) := $(CLOSED_$(g)))))
endif
HD_MODS     = $(foreach g,$(GROUPS),$(MOD_$(g)))
HD_GEOMS    = $(call hd_uniq,$(foreach g,$(GROUPS),$(GEOM_$(g))))
HD_RADMATS  = $(call hd_uniq,$(foreach g,$(GROUPS),$(filter %.rad,$(MAT_$(g)))))
HD_XMLS     = $(call hd_uniq,$(foreach g,$(GROUPS),$(filter %.xml,$(MAT_$(g)))))
HD_VNAMES   = $(foreach v,$(VIEWS),$(call hd_vname,$(v)))
HD_SNAMES   = $(foreach s,$(SENSORS),$(call hd_vname,$(s)))
HD_FISHEYE_VIEWS = $(foreach v,$(VIEWS),$(if $(shell grep -Eq -- '-vt[ah]' $(v) 2>/dev/null && grep -Eq -- '-vh +180' $(v) 2>/dev/null && echo y),$(v)))
HD_GLARE    = $(foreach v,$(GLARE_VIEWS),$(call hd_vname,$(v)))
HD_SHADE    = $(strip $(foreach g,$(GROUPS),$(CLOSED_$(g))))
export RAYPATH := $(subst $(space),:,$(strip . $(BSDFPATH) $(patsubst %/,%,$(sort $(dir $(HD_XMLS))))))
STAGE  = $(HELIODON_PIPE)/stage.sh $(OUT)/timings.txt
SPLIT  = awk -f $(HELIODON_PIPE)/scene.awk
# ---- daylight-coefficient folders, made whole or in record pieces (DC_PIECES) ----
# Each DC command runs in a folder of its own with output names relative to it (pipeline/dcrun.sh), so
# a whole run and the pieces of a split one write the same headers; rcmerge(1) joins the pieces of
# image rows (views) or points (sensor files) into the folder one run writes, byte for byte.  A folder
# gets min(DC_PIECES, its rows) pieces; with one it is made whole.
ABSOUT = $(abspath $(OUT))
HD_PIECED :=
# hd_dc TARGET, PREREQUISITES, TIMING NAME, RECORDS, RECORDS PER ROW, NAME OF THE COMMAND VARIABLE
define hd_dc
HD_PIECED += $(1)
$(1)_NP := $$(shell n=$(DC_PIECES); r=$$$$(( ($(4)) / ($(5)) )); echo $$$$(( n < r ? n : r )))
ifeq ($$($(1)_NP),1)
$(1): $(2)
	$(HELIODON_PIPE)/dcrun.sh $(1) all 1 $$$$(($(4))) $(5) $(ABSOUT)/timings.txt $(3) '$$($(6))'
else
$(1)_PIECES := $$(foreach k,$$(shell seq 0 $$$$(( $$($(1)_NP) - 1 ))),$(1).p/$$(k))
$(1).p/%: $(2)
	$(HELIODON_PIPE)/dcrun.sh $(1) $$* $$($(1)_NP) $$$$(($(4))) $(5) $(ABSOUT)/timings.txt $(3) '$$($(6))'
$(1): $$($(1)_PIECES)
	rm -rf $$@.tmp && rcmerge -d $$@.tmp $$^ && rm -rf $$@ && mv $$@.tmp $$@
endif
endef
# commit: rename the temporary output of a stage to its final name
define commit
mv -f $@.tmp $@
endef
ifeq ($(KEEPALL),1)
GENSUNS_A = -a
endif

.PHONY: all preflight clean-run compose-records
all: $(if $(filter slurm,$(SUBMIT)),submit,$(OUT)/report/index.html)

HD_TOP2 := $(if $(HD_SHADE),$(if $(filter open-pass closed,$(STATE)),,1))
ifeq ($(HD_TOP2),1)
# ==== two-pass operated shade: open run, closed run (sharing suns and masks), schedule per view ====
SUB = $(MAKE) --no-print-directory SHADE_LIMIT=$(SHADE_LIMIT)
SUB_OPEN = $(SUB) STATE=open-pass OUT=$(OUT)/open SHARE=
SUB_CLOSED = $(SUB) STATE=closed OUT=$(OUT)/closed SHARE=$(OUT)/open
.PHONY: pass_open pass_closed
$(OUT)/preflight.ok:
	@$(SUB_OPEN) $(OUT)/open/preflight.ok
	@$(SUB_CLOSED) $(OUT)/closed/preflight.ok
	@mkdir -p $(OUT) && touch $@
preflight: $(OUT)/preflight.ok
pass_open: $(OUT)/preflight.ok
	$(SUB_OPEN) all-annual
pass_closed: pass_open
	$(SUB_CLOSED) all-annual
define schedule_view
$(OUT)/$(1)/annual.csv $(OUT)/$(1)/hours.log &: pass_closed
	mkdir -p $(OUT)/$(1)
	$(HELIODON_PIPE)/stage.sh $(OUT)/schedule_time.txt schedule_$(1) pmcompose -schedule $(OUT)/open/$(1)/annual.csv \
	  $(OUT)/open/$(1)/hours.log $(OUT)/closed/$(1)/annual.csv $(OUT)/closed/$(1)/hours.log -c $(SHADE_LIMIT) \
	  -o $(OUT)/$(1)/annual.csv -Y $(OUT)/$(1)/schedule.csv -L $(OUT)/$(1)/hours.log -S $(OUT)/$(1)/summary.txt -t
$(OUT)/$(1)/selected.done: $(OUT)/$(1)/annual.csv
	rm -rf $(OUT)/$(1)/selected.tmp && mkdir -p $(OUT)/$(1)/selected.tmp
	recs=$$$$(cbdmreport -n $(NSELECT) -select $(OUT)/$(1)/hours.log); \
	ro=$$$$(awk -F, -v r="$$$$recs" 'BEGIN{n=split(r,a,",");for(i=1;i<=n;i++)w[a[i]]=1} NR>1 && ($$$$2 in w) && $$$$9==0 {printf "%s%s",s,$$$$2; s=","}' $(OUT)/$(1)/schedule.csv); \
	rc=$$$$(awk -F, -v r="$$$$recs" 'BEGIN{n=split(r,a,",");for(i=1;i<=n;i++)w[a[i]]=1} NR>1 && ($$$$2 in w) && $$$$9==1 {printf "%s%s",s,$$$$2; s=","}' $(OUT)/$(1)/schedule.csv); \
	if [ -n "$$$$ro" ]; then $(SUB_OPEN) compose-records VIEW1=$(1) RECORDS=$$$$ro IMGDIR=$(OUT)/$(1)/selected.tmp; fi; \
	if [ -n "$$$$rc" ]; then $(SUB_CLOSED) compose-records VIEW1=$(1) RECORDS=$$$$rc IMGDIR=$(OUT)/$(1)/selected.tmp; fi
	rm -rf $(OUT)/$(1)/selected && mv $(OUT)/$(1)/selected.tmp $(OUT)/$(1)/selected
	touch $$@
endef
$(foreach v,$(HD_GLARE),$(eval $(call schedule_view,$(v))))
$(OUT)/params.txt: pass_closed
	{ echo "operated shade = two passes, open / closed (closed when the view's open DGP >= $(SHADE_LIMIT))"; \
	  cat $(OUT)/open/params.txt; } > $@.tmp && $(commit)
$(OUT)/timings.txt: pass_closed $(foreach v,$(HD_GLARE),$(OUT)/$(v)/annual.csv)
	{ sed 's/^/open_/' $(OUT)/open/timings.txt; sed 's/^/closed_/' $(OUT)/closed/timings.txt; cat $(OUT)/schedule_time.txt; } > $@.tmp && $(commit)
HD_REPORT_VIEWS = $(HD_GLARE)
HD_REPORT_OPEN = 1
HD_REPORT_DEPS = $(foreach v,$(HD_GLARE),$(OUT)/$(v)/selected.done) $(OUT)/params.txt $(OUT)/timings.txt pass_closed
HD_SENSOR_DIR = $(OUT)/open
include $(HELIODON_PIPE)/report.mk
else
# ==================================================== single pass (or one pass of the two) ====
.PHONY: all-annual
all-annual: $(foreach v,$(HD_VNAMES),$(OUT)/$(v)/annual.done) $(if $(filter closed,$(STATE)),,$(foreach s,$(HD_SNAMES),$(OUT)/$(s)/metrics.csv)) $(OUT)/params.txt

# ---- checks that must fail before anything long starts ----
HD_ERR = echo "heliodon-pipeline: $(1)" >&2; exit 1
$(OUT)/preflight.ok: $(wildcard $(VIEWS) $(SENSORS) $(WEATHER)) $(HELIODON_PIPE)/preflight.sh
	@mkdir -p $(OUT)
	@HD_GROUPS="$(GROUPS)" HD_SCENE="$(SCENE)" HD_VIEWS="$(VIEWS)" HD_GLARE_VIEWS="$(GLARE_VIEWS)" \
	  HD_SENSORS="$(SENSORS)" HD_WEATHER="$(WEATHER)" HD_GROUND="$(GROUND_MOD)" HD_SKYMETHOD="$(SKYMETHOD)" \
	  HD_SHADE="$(HD_SHADE)" HD_STATE="$(STATE)" HD_SKYMF="$(SKYMF)" \
	  $(foreach g,$(GROUPS),HD_GEOM_$(g)="$(GEOM_$(g))" HD_MOD_$(g)="$(MOD_$(g))" HD_MAT_$(g)="$(MAT_$(g))" \
	    HD_KLEMS_$(g)="$(KLEMS_$(g))" HD_UP_$(g)="$(UP_$(g))") \
	  $(HELIODON_PIPE)/preflight.sh $(OUT)
	@rm -f $(OUT)/timings.txt
	@touch $@
preflight: $(OUT)/preflight.ok

# ---- the scene: materials of the window groups, the room without them, the exterior ground ----
$(OUT)/mat.rad: $(OUT)/preflight.ok $(wildcard $(HD_RADMATS))
	{ echo "# window-group materials ($(STATE))"; \
	  $(foreach g,$(GROUPS),$(if $(filter %.xml,$(MAT_$(g))),echo "void BSDF $(MOD_$(g)) 6 0 $(abspath $(MAT_$(g))) $(UP_$(g)) . 0 0";) \
	    $(if $(filter glass,$(MAT_$(g))),echo "void glass $(MOD_$(g)) 0 0 3 .96 .96 .96";)) \
	  $(foreach f,$(HD_RADMATS),cat $(f);) } > $@.tmp && $(commit)
$(OUT)/scene/all.rad: $(OUT)/preflight.ok $(wildcard $(call hd_uniq,$(SCENE) $(HD_GEOMS)))
	mkdir -p $(OUT)/scene
	xform $(call hd_uniq,$(SCENE) $(HD_GEOMS)) > $@.tmp && $(commit)
$(OUT)/scene/room.rad: $(OUT)/scene/all.rad
	$(SPLIT) -v mode=room -v mods="$(HD_MODS)" -v ground="$(GROUND_MOD)" -v name=scene $< > $@.tmp && $(commit)
$(OUT)/scene/ground.rad: $(OUT)/scene/all.rad
	$(SPLIT) -v mode=ground -v ground="$(GROUND_MOD)" -v name=scene $< > $@.tmp && $(commit)
$(OUT)/scene/win.rad: $(OUT)/scene/all.rad
	$(SPLIT) -v mode=win -v mods="$(HD_MODS)" -v name=scene $< > $@.tmp && $(commit)
$(OUT)/scene/mask.rad: $(OUT)/preflight.ok
	mkdir -p $(OUT)/scene
	{ $(foreach m,$(HD_MODS),echo "void glow $(m) 0 0 4 1 1 1 0";) } > $@.tmp && $(commit)
ifeq ($(GROUNDSUN),sun)
HD_SKYGROUND = $(OUT)/scene/ground.rad
endif
ROOM_SKY = $(OUT)/scene/room.rad $(HD_SKYGROUND) $(OUT)/scene/win.rad
ROOM_ALL = $(OUT)/scene/room.rad $(OUT)/scene/ground.rad $(OUT)/scene/win.rad

# ---- sun: sources, photon map ----
ifeq ($(SHARE),)
$(OUT)/suns.rad $(OUT)/mods.txt &: $(OUT)/preflight.ok
	$(STAGE) gensuns gensuns -v -m $(MF) $(GENSUNS_A) -M $(OUT)/mods.txt.tmp -o $(OUT)/suns.rad.tmp $(WEATHER)
	mv -f $(OUT)/mods.txt.tmp $(OUT)/mods.txt && mv -f $(OUT)/suns.rad.tmp $(OUT)/suns.rad
else
$(OUT)/suns.rad $(OUT)/mods.txt &: $(OUT)/preflight.ok $(SHARE)/suns.rad $(SHARE)/mods.txt
	cp $(SHARE)/mods.txt $(OUT)/mods.txt.tmp && mv -f $(OUT)/mods.txt.tmp $(OUT)/mods.txt
	cp $(SHARE)/suns.rad $(OUT)/suns.rad.tmp && mv -f $(OUT)/suns.rad.tmp $(OUT)/suns.rad
endif
# DC_sun's scene leaves the exterior ground out: its sunlit term is the sky part's ground glow
# (docs/design/pipeline.md, "Sunlight reflected by the exterior"); fensun.oct keeps it.
$(OUT)/sun.oct: $(OUT)/suns.rad $(OUT)/mat.rad $(ROOM_SKY)
	oconv $(OUT)/mat.rad $(ROOM_SKY) $(OUT)/suns.rad > $@.tmp && $(commit)
$(OUT)/fensun.oct: $(OUT)/suns.rad $(OUT)/mat.rad $(ROOM_ALL)
	oconv $(OUT)/mat.rad $(ROOM_ALL) $(OUT)/suns.rad > $@.tmp && $(commit)
ifeq ($(PM_SHARDS),)
$(OUT)/sun.cpm: $(OUT)/sun.oct
	rm -f $@.tmp.cpm
	$(STAGE) mkpmap mkpmap -apC $@.tmp.cpm $(PHOTONS) -apr $(PM_SEED) $(foreach m,$(HD_MODS),-apo $(m)) -n $(NPROC) $(OUT)/sun.oct
	mv -f $@.tmp.cpm $@
else
# PM_SHARDS=N: the map is built as N emission shards (mkpmap -apH k N, one task each on a cluster)
# and merged (mkpmap -apJ); the merged map's photons are those of the single run, byte for byte.
HD_PM_SHARDS = $(foreach k,$(shell seq 0 $$(($(PM_SHARDS) - 1))),$(OUT)/pm/shard$(k).cpm)
$(OUT)/pm/shard%.cpm: $(OUT)/sun.oct
	mkdir -p $(OUT)/pm && rm -f $@.tmp.cpm
	$(STAGE) mkpmap_shard$* mkpmap -apC $@.tmp.cpm $(PHOTONS) -apr $(PM_SEED) $(foreach m,$(HD_MODS),-apo $(m)) -apH $* $(PM_SHARDS) -n $(NPROC) $(OUT)/sun.oct
	mv -f $@.tmp.cpm $@
$(OUT)/sun.cpm: $(HD_PM_SHARDS)
	rm -f $@.tmp.cpm
	$(STAGE) mkpmap_merge mkpmap -apJ $@.tmp.cpm $(HD_PM_SHARDS)
	mv -f $@.tmp.cpm $@
endif

# the sun modifiers in units of SUN_UNIT (DC_sun per unit); sunits.done lists the units
$(OUT)/sunits.done: $(OUT)/mods.txt
	rm -rf $(OUT)/sunits $(OUT)/sunits.tmp && mkdir -p $(OUT)/sunits.tmp
	awk -v n=$(SUN_UNIT) -v d=$(OUT)/sunits.tmp '{f = sprintf("%s/%03d.txt", d, int((NR - 1) / n)); print > f}' $(OUT)/mods.txt
	mv $(OUT)/sunits.tmp $(OUT)/sunits
	ls $(OUT)/sunits | sed 's/\.txt$$//' > $@.tmp && $(commit)

# ---- sky scenes ----
$(OUT)/sky.oct: $(OUT)/mat.rad $(ROOM_SKY)
	oconv $(OUT)/mat.rad $(ROOM_SKY) $(HELIODON_PIPE)/skydc.rad > $@.tmp && $(commit)
$(OUT)/skyg.oct: $(OUT)/mat.rad $(ROOM_ALL)
	oconv $(OUT)/mat.rad $(ROOM_ALL) $(HELIODON_PIPE)/skydc.rad > $@.tmp && $(commit)
$(OUT)/mask.oct: $(OUT)/scene/mask.rad $(ROOM_ALL)
	oconv $(OUT)/scene/mask.rad $(ROOM_ALL) > $@.tmp && $(commit)
ifeq ($(SUN)$(FENSUN),11)
FENOCT = $(OUT)/skyg.oct
else
FENOCT = $(OUT)/sky.oct
endif

# ---- sunlit fraction of the exterior ground per sun patch (pmcompose -G) ----
# Points of the exterior ground the windows see: by default rays from stratified points of the
# window surfaces (cosine-distributed outwards) traced to their first hit; those landing on the
# ground (GROUND_MOD) are kept.  GROUNDPTS_CMD replaces this by a case's own generator.
ifeq ($(GROUNDPTS_CMD),)
$(OUT)/groundpts.txt: $(OUT)/scene/win.rad $(OUT)/fensun.oct
	awk -v n=$(GROUNDPTS) -f $(HELIODON_PIPE)/winrays.awk $(OUT)/scene/win.rad | \
	  rtrace -h -fa -ab 0 -dj 0 -oMpn $(OUT)/fensun.oct | \
	  awk -v g="$(GROUND_MOD)" 'BEGIN{n=split(g,a," ");for(i=1;i<=n;i++)G[a[i]]=1} ($$1 in G) {printf "%.4f %.4f %.4f %.6f %.6f %.6f\n", $$2+0.002*$$5, $$3+0.002*$$6, $$4+0.002*$$7, $$5, $$6, $$7}' > $@.tmp
	@test -s $@.tmp || { echo "heliodon-pipeline: GROUND_MOD '$(GROUND_MOD)': no ground point seen from the windows" >&2; rm -f $@.tmp; exit 1; }
	$(commit)
else
$(OUT)/groundpts.txt: $(OUT)/preflight.ok
	$(GROUNDPTS_CMD) > $@.tmp && $(commit)
endif
$(OUT)/groundsun.txt: $(OUT)/fensun.oct $(OUT)/suns.rad $(OUT)/mods.txt $(OUT)/groundpts.txt
	oconv $(OUT)/suns.rad > $(OUT)/sunsonly.oct
	$(STAGE) groundsun sh -c 'rcontrib -h -fa -I -ab 0 -dj 0 -n $(NPROC) -M $(OUT)/mods.txt $(OUT)/fensun.oct < $(OUT)/groundpts.txt > $(OUT)/gs_e.txt && \
	  rcontrib -h -fa -I -ab 0 -dj 0 -n $(NPROC) -M $(OUT)/mods.txt $(OUT)/sunsonly.oct < $(OUT)/groundpts.txt > $(OUT)/gs_e0.txt'
	{ echo "# sunlit fraction of the exterior ground seen from the windows, per sun patch ($$(wc -l < $(OUT)/groundpts.txt) ground points)"; \
	  paste $(OUT)/gs_e.txt $(OUT)/gs_e0.txt | awk -v m="$$(tr '\n' ' ' < $(OUT)/mods.txt)" \
	    'BEGIN {k = split(m, mod, " ")} {for (j = 1; j <= k; j++) {e[j] += $$(3 * j - 2); e0[j] += $$(3 * (k + j) - 2)}} \
	     END {for (j = 1; j <= k; j++) {p = mod[j]; sub(/^solar/, "", p); printf("%s %.4f\n", p, (e0[j] > 0 ? e[j] / e0[j] : 1))}}'; } > $@.tmp && $(commit)
ifeq ($(SUN),1)
ifeq ($(GROUNDSUN),sky)
ifneq ($(GROUND_MOD),)
GROUNDDEPS = $(OUT)/groundsun.txt
GROUNDARGS = -G $(ABSOUT)/groundsun.txt
endif
endif
endif

# ---- three-phase sky part: D and T*D per group (shared by the views) ----
comma := ,
space := $(eval) $(eval)
hd_ux = $(patsubst 0$(comma)0$(comma)1,Z,$(subst $(space),$(comma),$(strip $1)))
define group3pm
$(OUT)/tx_$(1).rad: $(OUT)/scene/win.rad
	{ echo "#@rfluxmtx h=kf u=$(call hd_ux,$(UP_$(1)))"; echo "void glow $(1)_tx 0 0 4 1 1 1 0"; \
	  $(SPLIT) -v mode=sel -v mod=$(MOD_$(1)) -v newmod=$(1)_tx -v name=win.rad $(OUT)/scene/win.rad; } > $$@.tmp && mv -f $$@.tmp $$@
$(OUT)/d_$(1).mtx: $(OUT)/tx_$(1).rad $(OUT)/scene/room.rad $(HD_SKYGROUND)
	$(STAGE) rfluxmtx_D_$(1) rfluxmtx -n $(NPROC) $(D_OPTS) $(OUT)/tx_$(1).rad $(HELIODON_PIPE)/sky_rx.rad $(OUT)/scene/room.rad $(HD_SKYGROUND) > $$@.tmp
	mv -f $$@.tmp $$@
$(OUT)/td_$(1).mtx: $(OUT)/d_$(1).mtx
	rmtxop $(KLEMS_$(1)) $(OUT)/d_$(1).mtx > $$@.tmp && mv -f $$@.tmp $$@
endef
ifeq ($(SKYMETHOD),3pm)
$(foreach g,$(GROUPS),$(eval $(call group3pm,$(g))))
endif

# ---------------------------------------------------------------- per view
ifeq ($(IMAGES),1)
HOURLY_OPT = 1
endif
define view_rules
# $(1) = view name, $(2) = view file
$(1)_VW = -vf $(2) -x $(RES) -y $(RES)
$(1)_VWA = -vf $(abspath $(2)) -x $(RES) -y $(RES)
$(1)_RCV = rcontrib $$$$HD_R -ffc $$$$(vwrays -d $$($(1)_VWA)) -n $(NPROC)
$(1)_GLARE = $(if $(filter $(1),$(HD_GLARE)),1,)
$(OUT)/$(1)/mask.hdr: $(if $(SHARE),$(SHARE)/$(1)/mask.hdr,$(OUT)/mask.oct) $(2)
	mkdir -p $(OUT)/$(1)
	$(if $(SHARE),cp $(SHARE)/$(1)/mask.hdr $$@.tmp,$(STAGE) mask_$(1) rpict $$($(1)_VW) -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 $(OUT)/mask.oct > $$@.tmp)
	mv -f $$@.tmp $$@
ifeq ($(SUNMETHOD),pm)
ifeq ($(SUN_UNIT),0)
$(1)_CMD_sun = vwrays -ff $$($(1)_VWA) | $$($(1)_RCV) $(SUN_OPTS) -ap $(ABSOUT)/sun.cpm $(BANDWIDTH) -o %s.hdr -M $(ABSOUT)/mods.txt $(ABSOUT)/sun.oct
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcsun,$(OUT)/sun.cpm $(OUT)/mods.txt $(2),rcontrib_sun_$(1),$(RES)*$(RES),$(RES),$(1)_CMD_sun))
else
# SUN_UNIT=N: DC_sun in units of N suns (sunits/NNN.txt), each unit one rcontrib run (one task on a
# cluster); the units' pictures are then gathered into dcsun/ (the same files whatever the task count)
$(OUT)/$(1)/dcsun.u/%: $(OUT)/sun.cpm $(OUT)/sunits.done $(2)
	rm -rf $$@.tmp && mkdir -p $$@.tmp
	$(STAGE) rcontrib_sun_$(1)_$$* sh -c 'vwrays -ff $$($(1)_VW) | rcontrib -ffc $$$$(vwrays -d $$($(1)_VW)) -n $(NPROC) $(SUN_OPTS) -ap $(OUT)/sun.cpm $(BANDWIDTH) -o $$@.tmp/%s.hdr -M $(OUT)/sunits/$$*.txt $(OUT)/sun.oct'
	rm -rf $$@ && mv $$@.tmp $$@
$(OUT)/$(1)/dcsun: $(OUT)/sun.cpm $(OUT)/sunits.done $(2)
	for u in $$$$(cat $(OUT)/sunits.done); do $(MAKE) --no-print-directory -f $(firstword $(MAKEFILE_LIST)) $(OUT)/$(1)/dcsun.u/$$$$u || exit 1; done
	rm -rf $$@.tmp && mkdir -p $$@.tmp
	for u in $$$$(cat $(OUT)/sunits.done); do ln -f $(OUT)/$(1)/dcsun.u/$$$$u/*.hdr $$@.tmp/ || exit 1; done
	rm -rf $$@ && mv $$@.tmp $$@
endif
else
$(1)_CMD_sun = vwrays -ff $$($(1)_VWA) | $$($(1)_RCV) $(SUN_BACKWARD_OPTS) -o %s.hdr -M $(ABSOUT)/mods.txt $(ABSOUT)/sun.oct
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcsun,$(OUT)/sun.oct $(OUT)/mods.txt $(2),rcontrib_sun_$(1),$(RES)*$(RES),$(RES),$(1)_CMD_sun))
endif
$(1)_CMD_sky = vwrays -ff $$($(1)_VWA) | $$($(1)_RCV) $(SKY_OPTS) -o %03d.hdr -f reinhart.cal -p MF=$(SKYMF) -b rbin -bn Nrbins -m skyglow $(ABSOUT)/sky.oct
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcsky,$(OUT)/sky.oct $(2),rcontrib_sky_$(1),$(RES)*$(RES),$(RES),$(1)_CMD_sky))
$(1)_CMD_fen = vwrays -ff $$($(1)_VWA) | pmmask -t $(ABSOUT)/$(1)/mask.hdr | $$($(1)_RCV) $(FEN_OPTS) -o %03d.hdr -f reinhart.cal -p MF=$(SKYMF) -b rbin -bn Nrbins -m skyglow $(abspath $(FENOCT))
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcfen,$(FENOCT) $(OUT)/$(1)/mask.hdr,rcontrib_fen_$(1),$(RES)*$(RES),$(RES),$(1)_CMD_fen))
$(1)_CMD_fensun = vwrays -ff -pj $(FENSUN_PJ) -c $(FENSUN_C) $$($(1)_VWA) | pmmask -n $(FENSUN_C) $(ABSOUT)/$(1)/mask.hdr | $$($(1)_RCV) -c $(FENSUN_C) $(FENSUN_OPTS) -o %s.hdr -M $(ABSOUT)/mods.txt $(ABSOUT)/fensun.oct
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcfensun,$(OUT)/fensun.oct $(OUT)/$(1)/mask.hdr $(OUT)/mods.txt,rcontrib_fensun_$(1),$(RES)*$(RES),$(RES),$(1)_CMD_fensun))
# three-phase V: all groups in one rfluxmtx run
$(OUT)/$(1)/rx_all.rad: $(OUT)/scene/win.rad
	mkdir -p $(OUT)/$(1)
	{ $(foreach g,$(GROUPS),echo "#@rfluxmtx h=kf u=$(call hd_ux,$(UP_$(g))) o=$(OUT)/$(1)/v.tmp/$(g)/%03d.hdr"; \
	  echo "void glow $(g)_rx 0 0 4 1 1 1 0"; $(SPLIT) -v mode=sel -v mod=$(MOD_$(g)) -v newmod=$(g)_rx -v name=win.rad $(OUT)/scene/win.rad;) } > $$@.tmp && mv -f $$@.tmp $$@
$(OUT)/$(1)/v: $(OUT)/$(1)/rx_all.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad
	rm -rf $$@.tmp && mkdir -p $(foreach g,$(GROUPS),$$@.tmp/$(g))
	$(STAGE) rfluxmtx_V_$(1) sh -c 'vwrays -ff $$($(1)_VW) | rfluxmtx -ffc $$$$(vwrays -d $$($(1)_VW)) -n $(NPROC) $(V_OPTS) - $(OUT)/$(1)/rx_all.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad'
	rm -rf $$@ && mv $$@.tmp $$@
ifeq ($(SKYMETHOD),3pm)
$(1)_SKYDEPS = $(OUT)/$(1)/v $(foreach g,$(GROUPS),$(OUT)/td_$(g).mtx)
$(1)_SKYARGS = $(foreach g,$(GROUPS),-V $(ABSOUT)/$(1)/v/$(g)/%03d.hdr $(ABSOUT)/td_$(g).mtx)
else
$(1)_SKYDEPS = $(OUT)/$(1)/dcsky
$(1)_SKYARGS = -k $(ABSOUT)/$(1)/dcsky/%03d.hdr
endif
ifeq ($(SUN),1)
$(1)_SUNDEPS = $(OUT)/$(1)/dcsun
$(1)_SUNARGS = -s $(ABSOUT)/$(1)/dcsun/solar%d.hdr
endif
ifeq ($(FEN),1)
$(1)_FENDEPS = $(OUT)/$(1)/dcfen
$(1)_FENARGS = -F $(ABSOUT)/$(1)/dcfen/%03d.hdr -K $(ABSOUT)/$(1)/mask.hdr
ifeq ($(SUN)$(FENSUN),11)
$(1)_FENDEPS += $(OUT)/$(1)/dcfensun
$(1)_FENARGS += -Fs $(ABSOUT)/$(1)/dcfensun/solar%d.hdr
endif
endif
$(1)_COMPOSE = pmcompose -n $(NPROC) -c $(SHADE_LIMIT) -w $(abspath $(WEATHER)) -vf $(abspath $(2)) -m $(MF) -ms $(SKYMF) $$($(1)_SUNARGS) $$($(1)_SKYARGS) $$($(1)_FENARGS) $(GROUNDARGS) $(if $(filter $(1),$(HD_GLARE)),,-noglare)
# the composition runs in a folder of its own with relative output names (the hourly images' headers
# hold the command line), whole or in HOUR_PIECES pieces of the daylight hours joined by pmcompose -J
$(1)_OUTS = $(if $(filter $(1),$(HD_GLARE)),annual.csv summary.txt) hours.log
$(1)_COMPOSE_IN = $$($(1)_COMPOSE) -t $(if $(filter $(1),$(HD_GLARE)),-o annual.csv -S summary.txt) -L hours.log \
  $(if $(HOURLY_OPT),-I hourly/h%04d.$(IMAGEFMT) $(if $(filter exr,$(IMAGEFMT)),-e))
ifeq ($(HOUR_PIECES),1)
$(OUT)/$(1)/annual.done: $$($(1)_SUNDEPS) $$($(1)_SKYDEPS) $$($(1)_FENDEPS) $(GROUNDDEPS)
	rm -rf $(OUT)/$(1)/compose.tmp && mkdir -p $(OUT)/$(1)/compose.tmp/hourly
	cd $(OUT)/$(1)/compose.tmp && $(HELIODON_PIPE)/stage.sh $(ABSOUT)/timings.txt pmcompose_$(1) $$($(1)_COMPOSE_IN)
	for f in $$($(1)_OUTS); do mv -f $(OUT)/$(1)/compose.tmp/$$$$f $(OUT)/$(1)/$$$$f; done
	$(if $(HOURLY_OPT),rm -rf $(OUT)/$(1)/hourly && mv $(OUT)/$(1)/compose.tmp/hourly $(OUT)/$(1)/hourly)
	rm -rf $(OUT)/$(1)/compose.tmp
	touch $$@
else
$(1)_HPIECES = $(foreach k,$(shell seq 0 $$(($(HOUR_PIECES) - 1))),$(OUT)/$(1)/compose.h/$(k))
$(OUT)/$(1)/compose.h/%: $$($(1)_SUNDEPS) $$($(1)_SKYDEPS) $$($(1)_FENDEPS) $(GROUNDDEPS)
	rm -rf $$@.tmp && mkdir -p $$@.tmp/hourly
	cd $$@.tmp && $(HELIODON_PIPE)/stage.sh $(ABSOUT)/timings.txt pmcompose_$(1)_h$$* $$($(1)_COMPOSE_IN) -H $$* $(HOUR_PIECES)
	rm -rf $$@ && mv $$@.tmp $$@
$(OUT)/$(1)/annual.done: $$($(1)_HPIECES)
	pmcompose -J $(if $(filter $(1),$(HD_GLARE)),-o $(OUT)/$(1)/annual.csv -S $(OUT)/$(1)/summary.txt) -L $(OUT)/$(1)/hours.log $$^
	$(if $(HOURLY_OPT),rm -rf $(OUT)/$(1)/hourly.tmp && mkdir -p $(OUT)/$(1)/hourly.tmp && \
	  for d in $$^; do ln -f $$$$d/hourly/* $(OUT)/$(1)/hourly.tmp/ || exit 1; done && \
	  rm -rf $(OUT)/$(1)/hourly && mv $(OUT)/$(1)/hourly.tmp $(OUT)/$(1)/hourly)
	touch $$@
endif
endef
$(foreach v,$(VIEWS),$(eval $(call view_rules,$(call hd_vname,$(v)),$(v))))

# hourly images of the given records (RECORDS=i,j,...) of view VIEW1 into IMGDIR (two-pass run)
compose-records:
	@test -n "$(RECORDS)" && test -n "$(IMGDIR)" && test -n "$(VIEW1)" || { echo "heliodon-pipeline: compose-records needs VIEW1=name RECORDS=i,j,... and IMGDIR=dir" >&2; exit 1; }
	mkdir -p $(IMGDIR)
	$($(VIEW1)_COMPOSE) -r $(RECORDS) -I $(IMGDIR)/h%04d.hdr -o /dev/null

# ---------------------------------------------------------------- sensor grids
# Each sensor file ("x y z dx dy dz" per point) is a one-row picture of irradiance coefficients:
# sun (photon map, final gather), sky (backward), direct sun only (-ab 0, for ASE); pmcompose -E
# composes every daylight hour (the same sky and sun vectors and ground fraction as the images).
define sensor_rules
# $(1) = sensor name, $(2) = file
$(1)_N = $$(shell awk 'NF >= 6 && $$$$1 !~ /^#/' $(2) | wc -l)
$(1)_RC = rcontrib $$$$HD_R -I -fac -x $$($(1)_N) -y 1 -n $(NPROC)
$(OUT)/$(1)/pts.txt: $(2) $(OUT)/preflight.ok
	mkdir -p $(OUT)/$(1)
	awk 'NF >= 6 && $$$$1 !~ /^#/ {print $$$$1, $$$$2, $$$$3, $$$$4, $$$$5, $$$$6}' $(2) > $$@.tmp && mv -f $$@.tmp $$@
$(1)_SCMD_sun = $$($(1)_RC) $(SENSOR_SUN_OPTS) $(if $(filter pm,$(SENSOR_SUNMETHOD)),-ap $(ABSOUT)/sun.cpm $(BANDWIDTH)) -o %s.hdr -M $(ABSOUT)/mods.txt $(ABSOUT)/sun.oct < $(ABSOUT)/$(1)/pts.txt
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcsun,$(if $(filter pm,$(SENSOR_SUNMETHOD)),$(OUT)/sun.cpm,$(OUT)/sun.oct) $(OUT)/mods.txt $(OUT)/$(1)/pts.txt,sensor_sun_$(1),$$($(1)_N),1,$(1)_SCMD_sun))
$(1)_SCMD_dsun = $$($(1)_RC) -ab 0 -dj 0 -o %s.hdr -M $(ABSOUT)/mods.txt $(ABSOUT)/sun.oct < $(ABSOUT)/$(1)/pts.txt
$$(eval $$(call hd_dc,$(OUT)/$(1)/dsun,$(OUT)/sun.oct $(OUT)/mods.txt $(OUT)/$(1)/pts.txt,sensor_direct_$(1),$$($(1)_N),1,$(1)_SCMD_dsun))
$(1)_SCMD_sky = $$($(1)_RC) $(SENSOR_SKY_OPTS) -o %03d.hdr -f reinhart.cal -p MF=$(SKYMF) -b rbin -bn Nrbins -m skyglow $(ABSOUT)/sky.oct < $(ABSOUT)/$(1)/pts.txt
$$(eval $$(call hd_dc,$(OUT)/$(1)/dcsky,$(OUT)/sky.oct $(OUT)/$(1)/pts.txt,sensor_sky_$(1),$$($(1)_N),1,$(1)_SCMD_sky))
$(OUT)/$(1)/illuminance.csv: $(OUT)/$(1)/dcsun $(OUT)/$(1)/dcsky $(GROUNDDEPS)
	$(STAGE) sensor_compose_$(1) pmcompose -n $(NPROC) -w $(WEATHER) -m $(MF) -ms $(SKYMF) -s $(OUT)/$(1)/dcsun/solar%d.hdr \
	  -k $(OUT)/$(1)/dcsky/%03d.hdr $(GROUNDARGS) -E $$@
$(OUT)/$(1)/direct.csv: $(OUT)/$(1)/dsun
	pmcompose -n $(NPROC) -w $(WEATHER) -m $(MF) -s $(OUT)/$(1)/dsun/solar%d.hdr -E $$@
$(OUT)/$(1)/metrics.csv: $(OUT)/$(1)/illuminance.csv $(OUT)/$(1)/direct.csv $(HELIODON_PIPE)/metrics.awk
	awk -f $(HELIODON_PIPE)/metrics.awk -v da=$(DA_LUX) -v sda=$(SDA_FRAC) -v ase=$(ASE_LUX) -v aseh=$(ASE_HOURS) \
	  -v udi="$(UDI_BANDS)" -v occ="$(OCC_HOURS)" -v summary=$(OUT)/$(1)/metrics_summary.txt.tmp \
	  $(WEATHER) $(OUT)/$(1)/pts.txt $(OUT)/$(1)/illuminance.csv $(OUT)/$(1)/direct.csv > $$@.tmp
	mv -f $(OUT)/$(1)/metrics_summary.txt.tmp $(OUT)/$(1)/metrics_summary.txt && mv -f $$@.tmp $$@
endef
$(foreach s,$(SENSORS),$(eval $(call sensor_rules,$(call hd_vname,$(s)),$(s))))

$(OUT)/params.txt: $(OUT)/preflight.ok
	{ echo "weather = $(WEATHER)"; echo "window groups = $(foreach g,$(GROUPS),$(g): $(MAT_$(g));)"; \
	  echo "views = $(VIEWS) (glare: $(or $(HD_GLARE),none))"; echo "sensor files = $(or $(SENSORS),none)"; \
	  echo "resolution = $(RES) x $(RES)"; echo "sun patches = Reinhart MF:$(MF)"; echo "sky coefficients = Reinhart MF:$(SKYMF)"; \
	  echo "sun part = $(if $(filter 1,$(SUN)),$(SUNMETHOD),left out (SUN=0))"; echo "sky method = $(SKYMETHOD)"; \
	  echo "fenestration refinement = $(if $(filter 1,$(FEN)),yes,no (FEN=0))"; echo "ground sun term = $(GROUNDSUN) (GROUNDSUN)"; \
	  echo "photons = $(PHOTONS)"; echo "bandwidth = $(BANDWIDTH)"; \
	  echo "DC_sun options = $(if $(filter pm,$(SUNMETHOD)),$(SUN_OPTS),$(SUN_BACKWARD_OPTS))"; \
	  echo "sky DC options = $(SKY_OPTS)"; echo "fenestration DC options = $(FEN_OPTS)"; \
	  $(if $(filter 11,$(SUN)$(FEN)),echo "fenestration sun DC options = $(FENSUN_OPTS) ($(FENSUN_C) rays per pixel with -pj $(FENSUN_PJ))";) \
	  $(if $(SENSORS),echo "sensor options = sun $(SENSOR_SUN_OPTS) / sky $(SENSOR_SKY_OPTS)";) echo "threads = $(NPROC)"; } > $@.tmp && $(commit)

ifeq ($(HD_SHADE),)
# ---- selected hours and the report (single pass) ----
define select_rules
$(OUT)/$(1)/selected.done: $(OUT)/$(1)/annual.done $(if $(HD_GLARE),$(OUT)/$(firstword $(HD_GLARE))/annual.done)
	rm -rf $(OUT)/$(1)/selected.tmp && mkdir -p $(OUT)/$(1)/selected.tmp
	$$($(1)_COMPOSE) -r $$$$(cbdmreport -n $(NSELECT) -select $(OUT)/$(or $(firstword $(HD_GLARE)),$(1))/hours.log) -I $(OUT)/$(1)/selected.tmp/h%04d.hdr -o /dev/null
	rm -rf $(OUT)/$(1)/selected && mv $(OUT)/$(1)/selected.tmp $(OUT)/$(1)/selected
	touch $$@
endef
$(foreach v,$(HD_VNAMES),$(eval $(call select_rules,$(v))))
HD_REPORT_VIEWS = $(HD_VNAMES)
HD_REPORT_DEPS = $(foreach v,$(HD_VNAMES),$(OUT)/$(v)/selected.done) $(OUT)/params.txt $(foreach s,$(HD_SNAMES),$(OUT)/$(s)/metrics.csv)
HD_SENSOR_DIR = $(OUT)
include $(HELIODON_PIPE)/report.mk
endif
endif

include $(HELIODON_PIPE)/slurm.mk

clean-run:
	rm -rf $(OUT)
include $(HELIODON_PIPE)/methods.mk

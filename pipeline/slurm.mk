# heliodon pipeline: submit mode for SLURM clusters (included by heliodon.mk).
#
#   make SUBMIT=slurm [SLURM_OPTS="--partition=p --account=a"]   (or: make submit)
#   make slurm-status        which stages and tasks are done, queued, failed
#   make slurm-resubmit      resubmit only the tasks that are not done
#   make slurm-plan          write the plan only ($(OUT)/slurm.plan), submit nothing
#
# The run is cut into stages of independent tasks (hdslurm(1): one sbatch --array job per stage,
# afterok dependencies between stages); every task is one make target of this pipeline, run in
# the case's folder with the same variables, so a task's output is the file the one-machine run
# makes, under the same name.  OUT must be on a folder every node sees.
#
#   prep     1 task      preflight, scene, octrees, suns, masks, ground fraction, sensor points
#   photons  PM_SHARDS   photon-map emission shards (mkpmap -apH k PM_SHARDS)
#   pmmerge  1 task      mkpmap -apJ: the map of the one-machine run
#   dc       1 per item  backward DCs that need no photon map: sky DC or V per view, the
#                        fenestration DCs, D (and T*D) per window group, sensor sky/direct DCs;
#                        a DC folder in DC_PIECES record pieces (image rows, sensor points) is
#                        one task per piece, joined (rcmerge) by the compose task
#   dcsun    1 per item  photon-map DC_sun per view (with SUN_UNIT=N: per view and unit of N suns;
#                        otherwise in DC_PIECES pieces) and per sensor file
#   dcjoin   1 per item  rcmerge of the DC folders made in pieces (DC_PIECES > 1), and the
#                        DC_sun folders gathered from their units (SUN_UNIT)
#   compose  1 per item  hourly composition + glare per view (in HOUR_PIECES pieces of the daylight
#                        hours), illuminance + metrics per sensor file
#   report   1 task      the joined compositions (pmcompose -J), selected hours, the HTML report
SUBMIT      ?=
SLURM_OPTS  ?=
SLURM_CPUS  ?= $(NPROC)
SLURM_MEM   ?= 4G
SLURM_PM_MEM ?= $(SLURM_MEM)
# a composition task holds the view's sky coefficient pictures as floats (RES² x 12 bytes x sky
# bins; the fenestration DC is merged into them) and, per thread, the working images and the DC_sun
# pictures of the hours in flight (pmcompose composes the hours in sun-patch order and frees a
# patch's picture after its last hour): RES² x (12 x sky bins + 400 bytes), plus 25 % and 256 MB;
# at least SLURM_MEM (1024² at SKYMF 1, any MF: about 2.9 GB)
SLURM_COMPOSE_MEM ?= $(shell awk -v r=$(RES) -v smf=$(SKYMF) -v m='$(SLURM_MEM)' \
  'BEGIN {nk = 145 * smf * smf + 1; mb = int(r * r * (12 * nk + 400) / 1048576 * 1.25) + 256; \
   u = toupper(substr(m, length(m))); v = m + 0; d = (u == "G") ? v * 1024 : (u == "T") ? v * 1048576 : (u == "K") ? v / 1024 : v; \
   if (mb < d) mb = d; printf "%dM", mb}')
# photon shards: one per 250 M photons by default (about 2 minutes each on 2 cores), at least 1
HD_PHOTONS_N = $(shell echo '$(PHOTONS)' | awk '{v = $$1 + 0; u = tolower(substr($$1, length($$1))); \
  if (u == "k") v *= 1e3; else if (u == "m") v *= 1e6; else if (u == "g") v *= 1e9; printf "%.0f", v}')
SLURM_PM_SHARDS ?= $(shell awk -v n=$(HD_PHOTONS_N) 'BEGIN {k = int((n + 249999999) / 250000000); print (k < 1 ? 1 : k)}')
HDSLURM ?= $(or $(wildcard $(HELIODON_PIPE)/../scripts/hdslurm),hdslurm)

.PHONY: submit slurm-plan slurm-status slurm-resubmit hd-prep

ifeq ($(HD_TOP2),1)
# ---- two-pass operated shade: the plans of the open and the closed pass (stages open_*, closed_*;
# the closed pass starts after the open pass's prep, whose suns and masks it shares), then the
# schedule and the report in one task
$(OUT)/slurm.plan: FORCE
	@mkdir -p $(OUT)
	@$(SUB_OPEN) HD_PLAN_PREFIX=open_ $(OUT)/open/slurm.plan
	@$(SUB_CLOSED) HD_PLAN_PREFIX=closed_ HD_PLAN_AFTER=open_prep $(OUT)/closed/slurm.plan
	@{ echo "# heliodon pipeline, SUBMIT=slurm, two-pass shade: $(abspath $(OUT)) (hdslurm(1) plan)"; \
	  echo '# name tasks after cpus mem command'; grep -hv '^#' $(OUT)/open/slurm.plan $(OUT)/closed/slurm.plan; \
	  echo 'report 1 open_annual,closed_annual $(SLURM_CPUS) $(SLURM_MEM) cd $(CURDIR) && $(MAKE) --no-print-directory -f $(abspath $(firstword $(MAKEFILE_LIST))) $(filter-out OUT=% SUBMIT=%,$(MAKEOVERRIDES)) OUT=$(abspath $(OUT)) SUBMIT= all'; } > $@.tmp
	@mv -f $@.tmp $@
else
# ---- the targets of each stage ----
HD_PM_NEEDED = $(if $(filter 1,$(SUN)),$(if $(or $(filter pm,$(SUNMETHOD)),$(and $(SENSORS),$(filter pm,$(SENSOR_SUNMETHOD)))),1))
HD_PREP_TARGETS = $(OUT)/preflight.ok $(OUT)/params.txt $(OUT)/mat.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad \
  $(OUT)/scene/win.rad $(OUT)/sky.oct $(OUT)/mods.txt $(OUT)/suns.rad $(OUT)/sun.oct $(OUT)/fensun.oct $(OUT)/skyg.oct \
  $(if $(filter 1,$(FEN)),$(if $(SHARE),,$(OUT)/mask.oct) $(foreach v,$(HD_VNAMES),$(OUT)/$(v)/mask.hdr)) \
  $(if $(filter 3pm,$(SKYMETHOD)),$(foreach v,$(HD_VNAMES),$(OUT)/$(v)/rx_all.rad) $(foreach g,$(GROUPS),$(OUT)/tx_$(g).rad)) \
  $(GROUNDDEPS) $(foreach s,$(HD_SNAMES),$(OUT)/$(s)/pts.txt)
HD_SENSOR_PM = $(filter pm,$(SENSOR_SUNMETHOD))
HD_DC_TARGETS = $(foreach v,$(HD_VNAMES),$($(v)_SKYDEPS) $($(v)_FENDEPS) $(if $(filter pm,$(SUNMETHOD)),,$($(v)_SUNDEPS))) \
  $(foreach s,$(HD_SNAMES),$(OUT)/$(s)/dcsky $(OUT)/$(s)/dsun $(if $(HD_SENSOR_PM),,$(OUT)/$(s)/dcsun))
HD_SUNITS = $(if $(filter-out 0,$(SUN_UNIT)),$(shell cat $(OUT)/sunits.done))
HD_DCSUN_TARGETS = $(if $(filter pm,$(SUNMETHOD)),$(foreach v,$(HD_VNAMES),$(if $(HD_SUNITS),$(foreach u,$(HD_SUNITS),$(OUT)/$(v)/dcsun.u/$(u)),$($(v)_SUNDEPS)))) \
  $(if $(HD_SENSOR_PM),$(foreach s,$(HD_SNAMES),$(OUT)/$(s)/dcsun))
# a DC folder made in record pieces is one task per piece; the dcjoin stage joins them
hd_pieces = $(foreach t,$(1),$(or $($(t)_PIECES),$(t)))
hd_joined = $(foreach t,$(1),$(if $($(t)_PIECES),$(t)))
HD_DCJOIN_TARGETS = $(call hd_joined,$(sort $(HD_DC_TARGETS) $(HD_DCSUN_TARGETS))) \
  $(if $(and $(HD_SUNITS),$(filter pm,$(SUNMETHOD))),$(foreach v,$(HD_VNAMES),$(OUT)/$(v)/dcsun))
# a view's composition in HOUR_PIECES pieces: one task per piece, joined by the report task
HD_COMPOSE_TARGETS = $(foreach v,$(HD_VNAMES),$(or $($(v)_HPIECES),$(OUT)/$(v)/annual.done)) \
  $(if $(filter closed,$(STATE)),,$(foreach s,$(HD_SNAMES),$(OUT)/$(s)/metrics.csv))
hd-prep: $(HD_PREP_TARGETS)

# every task runs make in the case's folder with the command line's variables (MAKEOVERRIDES
# keeps their spaces escaped for the shell), the absolute OUT and the shard count
HD_TASK_MAKE = cd $(CURDIR) && $(MAKE) --no-print-directory -f $(abspath $(firstword $(MAKEFILE_LIST))) \
  $(filter-out OUT=% SUBMIT=% PM_SHARDS=% DC_PIECES=% HOUR_PIECES=%,$(MAKEOVERRIDES)) OUT=$(abspath $(OUT)) \
  $(if $(HD_PM_NEEDED),PM_SHARDS=$(SLURM_PM_SHARDS)) DC_PIECES=$(DC_PIECES) HOUR_PIECES=$(HOUR_PIECES) SUBMIT=
# stage NAME, targets LIST, after AFTER: one task per target (task i makes the i-th)
hd_stage = $(if $(strip $(2)),echo '$(1) $(words $(2)) $(3) $(SLURM_CPUS) $(or $(4),$(SLURM_MEM)) t=($(2)); $(HD_TASK_MAKE) $${t[$$HD_TASK]}';)
# one pass of a two-pass run: stage names prefixed (HD_PLAN_PREFIX), its prep after HD_PLAN_AFTER,
# and its last stage the pass's joined results (all-annual) instead of the report
P := $(HD_PLAN_PREFIX)
hd_after = $(subst $(space),$(comma),$(strip $(addprefix $(P),$(1))))
$(OUT)/slurm.plan: FORCE $(if $(filter-out 0,$(SUN_UNIT)),$(OUT)/sunits.done)
	@mkdir -p $(OUT)
	@{ echo "# heliodon pipeline, SUBMIT=slurm: $(abspath $(OUT)) (hdslurm(1) plan)"; \
	  echo '# name tasks after cpus mem command'; \
	  echo '$(P)prep 1 $(or $(HD_PLAN_AFTER),-) $(SLURM_CPUS) $(SLURM_MEM) $(HD_TASK_MAKE) hd-prep'; \
	  $(if $(HD_PM_NEEDED),echo '$(P)photons $(SLURM_PM_SHARDS) $(P)prep $(SLURM_CPUS) $(SLURM_PM_MEM) $(HD_TASK_MAKE) $(abspath $(OUT))/pm/shard$$HD_TASK.cpm'; \
	    echo '$(P)pmmerge 1 $(P)photons 1 $(SLURM_PM_MEM) $(HD_TASK_MAKE) $(abspath $(OUT))/sun.cpm';) \
	  $(call hd_stage,$(P)dc,$(call hd_pieces,$(sort $(HD_DC_TARGETS))),$(P)prep) \
	  $(call hd_stage,$(P)dcsun,$(call hd_pieces,$(sort $(HD_DCSUN_TARGETS))),$(P)pmmerge) \
	  $(call hd_stage,$(P)dcjoin,$(HD_DCJOIN_TARGETS),$(call hd_after,$(if $(strip $(HD_DC_TARGETS)),dc) $(if $(strip $(HD_DCSUN_TARGETS)),dcsun))) \
	  $(call hd_stage,$(P)compose,$(HD_COMPOSE_TARGETS),$(call hd_after,prep $(if $(strip $(HD_DC_TARGETS)),dc) $(if $(strip $(HD_DCSUN_TARGETS)),dcsun) $(if $(strip $(HD_DCJOIN_TARGETS)),dcjoin)),$(SLURM_COMPOSE_MEM)) \
	  $(if $(P),echo '$(P)annual 1 $(P)compose $(SLURM_CPUS) $(SLURM_MEM) $(HD_TASK_MAKE) all-annual',echo 'report 1 compose $(SLURM_CPUS) $(SLURM_MEM) $(HD_TASK_MAKE) all'); } > $@.tmp
	@mv -f $@.tmp $@
endif
slurm-plan: $(OUT)/slurm.plan
	@echo "heliodon-pipeline: plan written to $(OUT)/slurm.plan"
submit: $(OUT)/preflight.ok $(OUT)/slurm.plan
	$(HDSLURM) submit $(OUT)/slurm.plan $(abspath $(OUT)) $(SLURM_OPTS)
slurm-status:
	@$(HDSLURM) status $(abspath $(OUT))
slurm-resubmit:
	$(HDSLURM) resubmit $(abspath $(OUT)) $(SLURM_OPTS)
.PHONY: FORCE
FORCE:

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
#                        fenestration DCs, D (and T*D) per window group, sensor sky/direct DCs
#   dcsun    1 per item  photon-map DC_sun per view (with SUN_UNIT=N: per view and unit of N suns)
#                        and per sensor file
#   compose  1 per item  hourly composition + glare per view, illuminance + metrics per sensor file
#   report   1 task      selected hours and the HTML report
SUBMIT      ?=
SLURM_OPTS  ?=
SLURM_CPUS  ?= $(NPROC)
SLURM_MEM   ?= 4G
SLURM_PM_MEM ?= $(SLURM_MEM)
# photon shards: one per 250 M photons by default (about 2 minutes each on 2 cores), at least 1
HD_PHOTONS_N = $(shell echo '$(PHOTONS)' | awk '{v = $$1 + 0; u = tolower(substr($$1, length($$1))); \
  if (u == "k") v *= 1e3; else if (u == "m") v *= 1e6; else if (u == "g") v *= 1e9; printf "%.0f", v}')
SLURM_PM_SHARDS ?= $(shell awk -v n=$(HD_PHOTONS_N) 'BEGIN {k = int((n + 249999999) / 250000000); print (k < 1 ? 1 : k)}')
HDSLURM ?= $(or $(wildcard $(HELIODON_PIPE)/../scripts/hdslurm),hdslurm)

.PHONY: submit slurm-plan slurm-status slurm-resubmit hd-prep

ifeq ($(HD_TOP2),1)
submit slurm-plan:
	@echo "heliodon-pipeline: SUBMIT=slurm does not run the two-pass operated shade yet (CLOSED_* set): run it on one machine" >&2; exit 1
else
# ---- the targets of each stage ----
HD_PM_NEEDED = $(if $(filter 1,$(SUN)),$(if $(or $(filter pm,$(SUNMETHOD)),$(and $(SENSORS),$(filter pm,$(SENSOR_SUNMETHOD)))),1))
HD_PREP_TARGETS = $(OUT)/preflight.ok $(OUT)/params.txt $(OUT)/mat.rad $(OUT)/scene/room.rad $(OUT)/scene/ground.rad \
  $(OUT)/scene/win.rad $(OUT)/sky.oct $(OUT)/mods.txt $(OUT)/suns.rad $(OUT)/sun.oct $(OUT)/fensun.oct $(OUT)/skyg.oct \
  $(if $(filter 1,$(FEN)),$(OUT)/mask.oct $(foreach v,$(HD_VNAMES),$(OUT)/$(v)/mask.hdr)) \
  $(if $(filter 3pm,$(SKYMETHOD)),$(foreach v,$(HD_VNAMES),$(OUT)/$(v)/rx_all.rad) $(foreach g,$(GROUPS),$(OUT)/tx_$(g).rad)) \
  $(GROUNDDEPS) $(foreach s,$(HD_SNAMES),$(OUT)/$(s)/pts.txt)
HD_SENSOR_PM = $(filter pm,$(SENSOR_SUNMETHOD))
HD_DC_TARGETS = $(foreach v,$(HD_VNAMES),$($(v)_SKYDEPS) $($(v)_FENDEPS) $(if $(filter pm,$(SUNMETHOD)),,$($(v)_SUNDEPS))) \
  $(foreach s,$(HD_SNAMES),$(OUT)/$(s)/dcsky $(OUT)/$(s)/dsun $(if $(HD_SENSOR_PM),,$(OUT)/$(s)/dcsun))
HD_SUNITS = $(if $(filter-out 0,$(SUN_UNIT)),$(shell cat $(OUT)/sunits.done))
HD_DCSUN_TARGETS = $(if $(filter pm,$(SUNMETHOD)),$(foreach v,$(HD_VNAMES),$(if $(HD_SUNITS),$(foreach u,$(HD_SUNITS),$(OUT)/$(v)/dcsun.u/$(u)),$($(v)_SUNDEPS)))) \
  $(if $(HD_SENSOR_PM),$(foreach s,$(HD_SNAMES),$(OUT)/$(s)/dcsun))
HD_COMPOSE_TARGETS = $(foreach v,$(HD_VNAMES),$(OUT)/$(v)/annual.done) \
  $(if $(filter closed,$(STATE)),,$(foreach s,$(HD_SNAMES),$(OUT)/$(s)/metrics.csv))
hd-prep: $(HD_PREP_TARGETS)

# every task runs make in the case's folder with the command line's variables (MAKEOVERRIDES
# keeps their spaces escaped for the shell), the absolute OUT and the shard count
HD_TASK_MAKE = cd $(CURDIR) && $(MAKE) --no-print-directory -f $(abspath $(firstword $(MAKEFILE_LIST))) \
  $(filter-out OUT=% SUBMIT=% PM_SHARDS=%,$(MAKEOVERRIDES)) OUT=$(abspath $(OUT)) \
  $(if $(HD_PM_NEEDED),PM_SHARDS=$(SLURM_PM_SHARDS)) SUBMIT=
# stage NAME, targets LIST, after AFTER: one task per target (task i makes the i-th)
hd_stage = $(if $(strip $(2)),echo '$(1) $(words $(2)) $(3) $(SLURM_CPUS) $(SLURM_MEM) t=($(2)); $(HD_TASK_MAKE) $${t[$$HD_TASK]}';)
$(OUT)/slurm.plan: FORCE $(if $(filter-out 0,$(SUN_UNIT)),$(OUT)/sunits.done)
	@mkdir -p $(OUT)
	@{ echo "# heliodon pipeline, SUBMIT=slurm: $(abspath $(OUT)) (hdslurm(1) plan)"; \
	  echo '# name tasks after cpus mem command'; \
	  echo 'prep 1 - $(SLURM_CPUS) $(SLURM_MEM) $(HD_TASK_MAKE) hd-prep'; \
	  $(if $(HD_PM_NEEDED),echo 'photons $(SLURM_PM_SHARDS) prep $(SLURM_CPUS) $(SLURM_PM_MEM) $(HD_TASK_MAKE) $(abspath $(OUT))/pm/shard$$HD_TASK.cpm'; \
	    echo 'pmmerge 1 photons 1 $(SLURM_PM_MEM) $(HD_TASK_MAKE) $(abspath $(OUT))/sun.cpm';) \
	  $(call hd_stage,dc,$(sort $(HD_DC_TARGETS)),prep) \
	  $(call hd_stage,dcsun,$(sort $(HD_DCSUN_TARGETS)),pmmerge) \
	  $(call hd_stage,compose,$(HD_COMPOSE_TARGETS),$(subst $(space),$(comma),$(strip prep $(if $(strip $(HD_DC_TARGETS)),dc) $(if $(strip $(HD_DCSUN_TARGETS)),dcsun)))) \
	  echo 'report 1 compose $(SLURM_CPUS) $(SLURM_MEM) $(HD_TASK_MAKE) all'; } > $@.tmp
	@mv -f $@.tmp $@
slurm-plan: $(OUT)/slurm.plan
	@echo "heliodon-pipeline: plan written to $(OUT)/slurm.plan"
submit: $(OUT)/preflight.ok $(OUT)/slurm.plan
	$(HDSLURM) submit $(OUT)/slurm.plan $(abspath $(OUT)) $(SLURM_OPTS)
endif
slurm-status:
	@$(HDSLURM) status $(abspath $(OUT))
slurm-resubmit:
	$(HDSLURM) resubmit $(abspath $(OUT)) $(SLURM_OPTS)
.PHONY: FORCE
FORCE:

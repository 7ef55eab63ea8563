# heliodon pipeline: "make reference", the methods against a converged backward rendering with the
# exact sun (the paper's Table 5; included by methods.mk; heliodon-pipeline(7)).
#
# For every glare view: the hour of largest disagreement between the methods of the run folder (the
# largest spread of their DGPs in OUT/compare/VIEW.csv; REF_PAIR="A B": the largest DGP_A - DGP_B) and
# REF_N - 1 more on other days, or the records REF_HOURS; for each, rpict with gendaylit's sky and exact sun (the window groups' own
# materials, the exterior ground) at REF_OS x RES with jittered rays (-pj 1: an unbiased estimate of
# each pixel's mean, which a sun sliver between slats narrower than the ray spacing needs) box-filtered
# to RES (pfilt -1: the paper's 8192^2 -> 1024^2) and once at RES (one ray per pixel centre, -pj 0), each method's picture of the hour (pmcompose -r), and
# per picture E_v, median, mean and maximum luminance, DGP, DGI and the glare sources' solid angle
# (evalglare -d) with false-colour PNGs (falsecolor, cbdmreport -png) side by side in
# OUT/compare/index.html; OUT/compare/VIEW_ref/table.csv holds the numbers, the wall time of each
# method against its error the chart OUT/compare/VIEW_time_error.svg.
REF_N    ?= 3
REF_HOURS ?=
REF_PAIR ?=
REF_OS   ?= 4
REF_OPTS ?= -ab 4 -ad 2048 -as 0 -aa 0 -lw 1e-5 -st 0
REF_FC   ?= -log 4 -s 100000
$(if $(filter $(REF_OS),1 2 3 4 5 6 7 8 16),,$(error heliodon-pipeline: REF_OS='$(REF_OS)': expected an oversampling factor 1..8 or 16))
.PHONY: reference
define ref_view
$(OUT)/compare/$(1)_ref/records.txt: $(OUT)/compare/$(1).csv $(HELIODON_PIPE)/reference.sh
	mkdir -p $(OUT)/compare/$(1)_ref
	$(HELIODON_PIPE)/reference.sh pick $$< $(REF_N) "$(REF_HOURS)" "$(REF_PAIR)" > $$@.tmp
	@test -s $$@.tmp || { echo "heliodon-pipeline: make reference: view $(1): no hour with two methods in $$< (run the methods first)" >&2; rm -f $$@.tmp; exit 1; }
	mv -f $$@.tmp $$@
$(OUT)/compare/$(1)_ref/table.csv: $(OUT)/compare/$(1)_ref/records.txt $(OUT)/records.txt $(OUT)/site.txt $(OUT)/mat.rad $(ROOM_ALL)
	d=$(OUT)/compare/$(1)_ref; for r in $$$$(cat $$$$d/records.txt); do \
	  [ -s $$$$d/ref_$$$$r.hdr ] && [ -s $$$$d/ref1_$$$$r.hdr ] && continue; \
	  $(HELIODON_PIPE)/reference.sh sky $$$$r $(OUT)/records.txt $(OUT)/site.txt > $$$$d/sky_$$$$r.rad && \
	  oconv $(OUT)/mat.rad $(ROOM_ALL) $$$$d/sky_$$$$r.rad > $$$$d/ref_$$$$r.oct && \
	  $(STAGE) reference_$(1)_$$$$r sh -c "rpict -vf $(2) -x $$$$(($(RES) * $(REF_OS))) -y $$$$(($(RES) * $(REF_OS))) -ps 1 -pj 1 -dj 0 $(REF_OPTS) \
	    $$$$d/ref_$$$$r.oct | pfilt -1 -x $(RES) -y $(RES) > $$$$d/ref_$$$$r.hdr.tmp" && mv -f $$$$d/ref_$$$$r.hdr.tmp $$$$d/ref_$$$$r.hdr && \
	  $(STAGE) reference1_$(1)_$$$$r rpict -vf $(2) -x $(RES) -y $(RES) -ps 1 -pj 0 -dj 0 $(REF_OPTS) $$$$d/ref_$$$$r.oct > $$$$d/ref1_$$$$r.hdr.tmp && \
	  mv -f $$$$d/ref1_$$$$r.hdr.tmp $$$$d/ref1_$$$$r.hdr && rm -f $$$$d/ref_$$$$r.oct || exit 1; done
	rl=$$$$(paste -sd, $(OUT)/compare/$(1)_ref/records.txt); d=$(OUT)/compare/$(1)_ref; \
	$(if $(wildcard $(OUT)/$(1)/annual.csv),$$($(1)_COMPOSE) -r $$$$rl -I $$$$d/pm_%d.hdr -o /dev/null &&) \
	$(if $(wildcard $(M3)/$(1)/annual.done),$$($(1)_3PM) -r $$$$rl -I $$$$d/3pm_%d.hdr -o /dev/null &&) \
	$(if $(wildcard $(M5)/$(1)/annual.done),$$($(1)_5PM) -r $$$$rl -I $$$$d/5pm_%d.hdr -o /dev/null &&) \
	$(HELIODON_PIPE)/reference.sh table $$$$d $(2) $(MI)/$(1)/annual.csv "$(REF_FC)" $(REF_OS) $$$$(cat $$$$d/records.txt)
endef
ifneq ($(HD_TOP2),1)
$(foreach v,$(HD_GLARE),$(eval $(call ref_view,$(v),$(call hd_vfile,$(v)))))
reference: $(foreach v,$(HD_GLARE),$(OUT)/compare/$(v)_ref/table.csv) compare
endif

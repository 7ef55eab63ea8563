# heliodon pipeline: the HTML report (included by heliodon.mk).  One section per view (glare views:
# cbdmreport's page in report/VIEW/, linked and summarised; other views: the selected hours'
# images) and one per sensor file (metrics table).  Needs HD_REPORT_VIEWS, HD_REPORT_DEPS,
# HD_SENSOR_DIR, HD_REPORT_OPEN (two-pass).
$(OUT)/report/index.html: $(HD_REPORT_DEPS) $(HELIODON_PIPE)/report.sh
	rm -rf $(OUT)/report.tmp && mkdir -p $(OUT)/report.tmp
	$(foreach v,$(filter $(HD_GLARE),$(HD_REPORT_VIEWS)),cat $(OUT)/$(v)/summary.txt $(NOTES) > $(OUT)/$(v)/notes.txt && \
	  $(HELIODON_PIPE)/stage.sh $(OUT)/timings.txt report_$(v) cbdmreport -c $(OUT)/$(v)/annual.csv \
	  $(if $(HD_REPORT_OPEN),-open $(OUT)/open/$(v)/annual.csv) -o $(OUT)/report.tmp/$(v) -s $(SHADE_LIMIT) \
	  -p $(OUT)/params.txt -T $(OUT)/timings.txt -N $(OUT)/$(v)/notes.txt -title "$(TITLE), view $(v)" $(OUT)/$(v)/selected/*.hdr;)
	$(HELIODON_PIPE)/report.sh $(OUT) $(OUT)/report.tmp "$(TITLE)" "$(HD_REPORT_VIEWS)" "$(HD_GLARE)" \
	  "$(HD_SNAMES)" $(HD_SENSOR_DIR) $(OUT)/params.txt > $(OUT)/report.tmp/index.html
	rm -rf $(OUT)/report && mv $(OUT)/report.tmp $(OUT)/report

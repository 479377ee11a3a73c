# The CLI's sources and the C API's GoogleTest suites, listed once for both builds: the catkin
# package (CMakeLists.txt) and the core built alone (src/core/CMakeLists.txt). Paths are from the
# repository's root. The allocation count is added where the sanitizers do not own malloc.
set(F3R_CLI_SOURCES
  src/cli/flex3rpr_sim.c src/cli/cli_options.c src/cli/cli_overrides.c src/cli/csv_rows.c
  src/cli/hold_table.c src/cli/model_reports.c src/cli/summary_json.c src/cli/run_report.c
  src/cli/sensor_columns.c)
set(F3R_CORE_GTESTS beam_modes beam_basis static_correction stages residual_jacobian linear_solver
    simulation scene_files effects hard_cases accuracy set_state state_space csv_number end_stops
    stop_stress sensors session measured_run kinds)

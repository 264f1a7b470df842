# The fuzz targets: fuzz/fuzz_<name>.cpp each. Included by fuzz/CMakeLists.txt (the libFuzzer programs) and by
# tests/CMakeLists.txt (fuzz_replay_test, which compiles them all into one program).
set(FF_FUZZ_TARGETS scene ply checkpoint frame surface ws_message http_request mesh mesh_checks)
# What each links (the replay test links them all).
set(FF_FUZZ_LIBS_scene ff_scene)
set(FF_FUZZ_LIBS_ply ff_io)
set(FF_FUZZ_LIBS_checkpoint ff_sim ff_metrics)
set(FF_FUZZ_LIBS_frame ff_server)
set(FF_FUZZ_LIBS_surface ff_server)
set(FF_FUZZ_LIBS_ws_message ff_server)
set(FF_FUZZ_LIBS_http_request ff_server Boost::headers)
set(FF_FUZZ_LIBS_mesh ff_io)
set(FF_FUZZ_LIBS_mesh_checks ff_io)

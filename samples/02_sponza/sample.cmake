# The GL samples read window keys and set the window title through GLFW (samples/common/sample_gl.h).
pkg_check_modules(GLOW_SAMPLES_GLFW REQUIRED IMPORTED_TARGET glfw3)
target_link_libraries(${SAMPLE_TARGET} PRIVATE PkgConfig::GLOW_SAMPLES_GLFW)

# The minimal CPU sample depends on the runtime alone (glow.h): no GL, no Embree, no glow_host.
set(SAMPLE_LIBS glow_runtime)

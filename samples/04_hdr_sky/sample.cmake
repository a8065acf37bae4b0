# The HDR sky sample: the runtime and the CPU host (glow_host: the sun's shadow rays and the SH sky at
# the surfels), and OpenEXR's C core to read the sky map (Debian: libopenexr-dev, as the tools need).
set(SAMPLE_LIBS glow_runtime glow_host)
find_package(OpenEXR REQUIRED)
target_link_libraries(${SAMPLE_TARGET} PRIVATE OpenEXR::OpenEXRCore)

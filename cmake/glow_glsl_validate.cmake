# glow_glsl_validate.cmake — script mode: runs glslangValidator on every composed kernel in DIR (written
# by glow_embed.cmake) and the composed shading-include checks (*.frag), failing the
# build with the validator's messages when one does not compile.
#   -DVALIDATOR=path -DDIR=dir -DSTAMP=file
file(GLOB files ${DIR}/*.comp ${DIR}/*.frag)
set(failed "")
foreach(f IN LISTS files)
  execute_process(COMMAND ${VALIDATOR} ${f} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message("${out}${err}")
    list(APPEND failed ${f})
  endif()
endforeach()
if(failed)
  message(FATAL_ERROR "glslangValidator rejected: ${failed}")
endif()
list(LENGTH files n)
message(STATUS "glslangValidator: ${n} shaders valid")
file(WRITE ${STAMP} "ok\n")

# Warning flags for Glow's own targets (STYLE §2.11 habit 1): errors only under GLOW_WERROR.
function(glow_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wshadow -Wstrict-prototypes -Wno-unused-parameter>
    $<$<BOOL:${GLOW_WERROR}>:-Werror>)
endfunction()

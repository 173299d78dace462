# handtrack_warnings(TARGET): strict warnings for handtrack's own code (never for third-party code).
function(handtrack_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
                              -Woverloaded-virtual>
    $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic -Wshadow>)
  if(HANDTRACK_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

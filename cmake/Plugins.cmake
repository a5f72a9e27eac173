# Ego controller plugins: C shared modules against include/vsd/sim/controller_abi.h,
# written to <build>/plugins (where the tests and the README's examples look).
function(vsd_add_controller_plugin target source)
  add_library(${target} MODULE ${source})
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR}/include)
  target_link_libraries(${target} PRIVATE m vsd_warnings)
  set_target_properties(${target} PROPERTIES
    C_STANDARD 11
    C_VISIBILITY_PRESET hidden
    LIBRARY_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/plugins)
endfunction()

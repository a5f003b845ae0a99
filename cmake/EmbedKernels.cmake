# Writes one C++ file that holds every kernel source (.cl, .h) as a string, keyed by its path
# relative to the repository root ("kernels/raster/raster.cl"). The OpenCL layer resolves
# #include lines against this table, so the binary runs from anywhere without kernel files.
function(gi_embed_kernels out_file)
  set(files ${ARGN})
  add_custom_command(
    OUTPUT ${out_file}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out_file} -DROOT=${CMAKE_SOURCE_DIR} "-DFILES=\"${files}\""
            -P ${CMAKE_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    DEPENDS ${files} ${CMAKE_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    COMMENT "Embedding OpenCL kernel sources")
endfunction()

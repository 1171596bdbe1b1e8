# Writes OUT, a C++ header with every DIR/*.glsl file as a NUL-terminated char array in
# namespace limn::shaders, named after the file ("patch.tesc.glsl" -> patch_tesc). Run by the
# render layer's build (src/render/CMakeLists.txt) whenever a shader changes.
file(GLOB files "${DIR}/*.glsl")
list(SORT files)
set(text "// Generated from src/render/shaders/*.glsl by cmake/embed_shaders.cmake: do not edit.\n")
string(APPEND text "#pragma once\n\nnamespace limn::shaders {\n")
foreach(f IN LISTS files)
  get_filename_component(name "${f}" NAME)
  string(REGEX REPLACE "\\.glsl$" "" name "${name}")
  string(REPLACE "." "_" name "${name}")
  file(READ "${f}" hex HEX)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," bytes "${hex}")
  string(APPEND text "inline constexpr char ${name}[] = {${bytes}'\\0'};\n")
endforeach()
string(APPEND text "}  // namespace limn::shaders\n")
file(WRITE "${OUT}.tmp" "${text}")
file(RENAME "${OUT}.tmp" "${OUT}")

# SPDX-License-Identifier: BSD-3-Clause
# cmake -DINPUT=viewer_bundle.js -DOUTPUT=viewer_bundle.cc -P embed.cmake
# The bundled page script as a C++ raw string (bayon::kViewerBundleJs), so
# that the bayon binary carries it and needs no files at run time.
file(READ "${INPUT}" script)
set(delimiter "bayon_js")
string(FIND "${script}" ")${delimiter}\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw string delimiter )${delimiter}\"")
endif()
# Inline in <script>, the text must not close the element early.
string(TOLOWER "${script}" lower)
string(FIND "${lower}" "</script" closing)
if(NOT closing EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains </script at offset ${closing}")
endif()
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by tools/viewer/embed.cmake; do not edit.\n"
  "namespace bayon {\n"
  "extern const char kViewerBundleJs[];\n"
  "const char kViewerBundleJs[] = R\"${delimiter}(${script})${delimiter}\";\n"
  "}  // namespace bayon\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")

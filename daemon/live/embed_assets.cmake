# embed_assets.cmake: turns the live page's files (daemon/live/web/) into one C file of byte
# arrays, so ribbond carries its page (no install step, no path to get wrong). Run by
# add_custom_command in this folder's CMakeLists with -DOUT=... -DFILES=a,b,c -DBASE=dir.
string(REPLACE "," ";" FILES "${FILES}")
set(src "/* Generated from daemon/live/web/ by embed_assets.cmake: do not edit. */\n#include <stddef.h>\n")
set(table "")
set(i 0)
foreach(f ${FILES})
  file(READ "${BASE}/${f}" hex HEX)
  string(LENGTH "${hex}" hlen)
  math(EXPR n "${hlen} / 2")
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  string(APPEND src "static const unsigned char live_file_${i}[] = {${bytes} 0};\n")
  string(APPEND table "    {\"${f}\", live_file_${i}, ${n}},\n")
  math(EXPR i "${i} + 1")
endforeach()
string(APPEND src "typedef struct live_embedded { const char *name; const unsigned char *data; size_t len; } live_embedded;\n")
string(APPEND src "const live_embedded live_embedded_files[] = {\n${table}    {0, 0, 0}\n};\n")
file(WRITE "${OUT}" "${src}")

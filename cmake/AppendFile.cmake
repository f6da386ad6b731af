# cmake -DTARGET_FILE=<file> -DTAIL_FILE=<file> -P AppendFile.cmake
file(READ ${TAIL_FILE} tail)
file(APPEND ${TARGET_FILE} "${tail}")

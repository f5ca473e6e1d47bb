# CMake toolchain file for Microchip MPLAB XC16 (xc16-gcc), dsPIC33F / PIC24 targets.
#
#   cmake -S firmware/hal/dspic33 -B build/xc16 -DCMAKE_TOOLCHAIN_FILE=firmware/cmake/xc16.cmake
#   cmake --build build/xc16            # -> build/xc16/whisker_board.elf and whisker_board.hex
#
# Cache variables:
#   XC16_ROOT  the XC16 install (the folder holding bin/xc16-gcc); default: the XC16_ROOT
#              environment variable, else the newest /opt/microchip/xc16/v*, else PATH
#   XC16_PART  device for -mcpu= and the linker script p<part>.gld (default 33FJ128MC802)
#   XC16_DFP   optional device family pack folder, passed as -mdfp=<dir>/xc16
#
# What it does: xc16-gcc is GCC 4.5 underneath but cannot link a program without a device, so
# CMake's compiler identification and test build are bypassed (the compiler is declared GNU
# 4.5.1 and "forced"); executables get the .elf suffix, and xc16_target(<tgt>) adds the device
# flags and an xc16-bin2hex post-build step that writes <tgt>.hex beside <tgt>.elf.
# When XC16 is missing, configuring stops here with a message saying what to install.

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR dsPIC33F)

set(XC16_PART "33FJ128MC802" CACHE STRING "XC16 device for -mcpu= (no dsPIC/PIC prefix)")
if(NOT DEFINED XC16_ROOT AND DEFINED ENV{XC16_ROOT})
  set(XC16_ROOT "$ENV{XC16_ROOT}")
endif()
set(XC16_ROOT "${XC16_ROOT}" CACHE PATH "MPLAB XC16 install folder (holds bin/xc16-gcc)")
set(XC16_DFP "" CACHE PATH "Optional device family pack folder for -mdfp (XC16 v2)")
# Values try_compile() projects must see (none run while the compiler is forced, but be safe).
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES XC16_ROOT XC16_PART XC16_DFP)

# ---- Find xc16-gcc: XC16_ROOT, then the newest /opt/microchip/xc16/v*, then PATH ----
set(_xc16_hints "")
if(XC16_ROOT)
  list(APPEND _xc16_hints "${XC16_ROOT}/bin" "${XC16_ROOT}")
endif()
file(GLOB _xc16_installs LIST_DIRECTORIES true "/opt/microchip/xc16/v*")
list(SORT _xc16_installs COMPARE NATURAL ORDER DESCENDING)
foreach(_dir IN LISTS _xc16_installs)
  list(APPEND _xc16_hints "${_dir}/bin")
endforeach()

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
if(XC16_ROOT)
  # An explicit root must be the one used: no silent fallback to another install.
  find_program(XC16_GCC NAMES xc16-gcc HINTS ${_xc16_hints} NO_DEFAULT_PATH)
else()
  find_program(XC16_GCC NAMES xc16-gcc HINTS ${_xc16_hints})
endif()

if(NOT XC16_GCC)
  if(XC16_ROOT)
    set(_xc16_where "XC16_ROOT=${XC16_ROOT} (no bin/xc16-gcc there)")
  else()
    set(_xc16_where "XC16_ROOT (not set), /opt/microchip/xc16/v*/bin and PATH")
  endif()
  unset(XC16_GCC CACHE) # search again on the next configure
  message(FATAL_ERROR
    "MPLAB XC16 compiler not found: no xc16-gcc in ${_xc16_where}.\n"
    "The dsPIC33 firmware (part ${XC16_PART}) is built with Microchip's MPLAB XC16 C compiler; "
    "the free edition is enough. To build it:\n"
    "  1. Install \"MPLAB XC16 Compiler\" for Linux from Microchip (run its .run installer as root); "
    "it installs to /opt/microchip/xc16/v<version>/ by default, which is searched automatically.\n"
    "  2. If it is installed elsewhere, pass the folder that holds bin/xc16-gcc: "
    "-DXC16_ROOT=/path/to/xc16/v<version> (or export XC16_ROOT=...), in a fresh build folder.\n"
    "Host builds and the firmware tests do not need XC16: configure the top-level project without "
    "this toolchain file (tools/run-tests.sh).")
endif()

get_filename_component(XC16_BIN_DIR "${XC16_GCC}" DIRECTORY)
find_program(XC16_BIN2HEX NAMES xc16-bin2hex HINTS "${XC16_BIN_DIR}" NO_DEFAULT_PATH)
if(NOT XC16_BIN2HEX)
  unset(XC16_BIN2HEX CACHE)
  message(FATAL_ERROR
    "MPLAB XC16 install at ${XC16_BIN_DIR} has xc16-gcc but no xc16-bin2hex, which turns the "
    ".elf into the .hex that MPLAB IPE flashes. Reinstall MPLAB XC16 from Microchip, or point "
    "-DXC16_ROOT at a complete install.")
endif()
find_program(XC16_AR NAMES xc16-ar HINTS "${XC16_BIN_DIR}" NO_DEFAULT_PATH)

# ---- The compiler, declared rather than identified ----
set(CMAKE_C_COMPILER "${XC16_GCC}")
set(CMAKE_C_COMPILER_ID GNU)          # xc16-gcc --version: "4.5.1 (XC16, Microchip v...)"
set(CMAKE_C_COMPILER_VERSION 4.5.1)
set(CMAKE_C_COMPILER_ID_RUN TRUE)     # skip CMakeCCompilerId.c (it cannot link without -mcpu)
set(CMAKE_C_COMPILER_FORCED TRUE)     # skip the test program and the ABI check
set(CMAKE_C_COMPILER_WORKS TRUE)
set(CMAKE_SIZEOF_VOID_P 2)            # 16-bit data pointers
if(XC16_AR)
  set(CMAKE_AR "${XC16_AR}" CACHE FILEPATH "XC16 archiver")
endif()

# Objects *.o, programs *.elf. CMake's Generic platform and C rules reset both after this file
# runs (to "" and .obj), so they are set again from a rules override, which is read last.
set(_xc16_rules "${CMAKE_BINARY_DIR}/CMakeFiles/xc16-rules.cmake")
file(WRITE "${_xc16_rules}"
  "set(CMAKE_C_OUTPUT_EXTENSION .o)\nset(CMAKE_EXECUTABLE_SUFFIX .elf)\n")
set(CMAKE_USER_MAKE_RULES_OVERRIDE "${_xc16_rules}")
set(CMAKE_EXECUTABLE_SUFFIX_C .elf)

set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)

# xc16_target(<target>): device flags, linker script, memory map, .elf suffix and the .hex.
# Call it for every executable that runs on the part.
function(xc16_target target)
  set(_dev -mcpu=${XC16_PART} -omf=elf)
  if(XC16_DFP)
    list(APPEND _dev "-mdfp=${XC16_DFP}/xc16")
  endif()
  target_compile_options(${target} PRIVATE ${_dev})
  target_link_options(${target} PRIVATE ${_dev}
    "-Wl,--script=p${XC16_PART}.gld,--heap=0,--report-mem,-Map=$<TARGET_FILE_DIR:${target}>/${target}.map")
  set_target_properties(${target} PROPERTIES SUFFIX .elf)
  # xc16-bin2hex writes <name>.hex next to <name>.elf; -a sorts the records by address. (The
  # byproduct path assumes the default output folder: BYPRODUCTS cannot name the target's.)
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND "${XC16_BIN2HEX}" "$<TARGET_FILE:${target}>" -a -omf=elf
    BYPRODUCTS "${CMAKE_CURRENT_BINARY_DIR}/${target}.hex"
    COMMENT "xc16-bin2hex: ${target}.hex"
    VERBATIM)
endfunction()

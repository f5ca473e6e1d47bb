# Writes help2man's include file of crunchhost's subcommands (cmake -P; host/app/CMakeLists.txt):
# a [SUBCOMMANDS] section with each subcommand's own --help, verbatim, so the man page is made
# from the program's help and nothing in it is written twice.
#   cmake -DCRUNCHHOST=path -DOUT=file -P man_subcommands.cmake
set(text "[SUBCOMMANDS]\nEach subcommand's own \\fB\\-\\-help\\fR:\n")
foreach(sub train sweep sweep-merge sweep-chart export)
  execute_process(COMMAND ${CRUNCHHOST} ${sub} --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${CRUNCHHOST} ${sub} --help exited ${rc}")
  endif()
  # CLI11 prints the path it was run by: the build tree's means nothing in a man page.
  string(REPLACE "${CRUNCHHOST}" "crunchhost" help "${help}")
  # roff: a backslash is an escape, and a line starting with . or ' is a request.
  string(REPLACE "\\" "\\e" help "${help}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")
  string(APPEND text ".SS ${sub}\n.nf\n${help}\n.fi\n")
endforeach()
file(WRITE ${OUT} "${text}")

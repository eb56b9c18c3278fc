# Writes a man page from a built program's own help, so the page cannot drift from the program.
# Run at build time as a script:
#   cmake -DPROGRAM=path -DNAME=robocal -DSECTION=1 -DSUMMARY="one line" [-DSUBCOMMANDS=ON]
#         [-DSEE_ALSO="robocald(8)"] [-DNOTES="text"] -DOUTPUT=robocal.1 -P man-from-help.cmake
# The page: NAME (SUMMARY), SYNOPSIS (the help's first paragraph, its usage lines), DESCRIPTION
# (the rest of `PROGRAM --help`), with SUBCOMMANDS a COMMANDS section holding
# `PROGRAM COMMAND --help` of every command `PROGRAM help` lists, then NOTES and SEE ALSO. The
# version in the header is `PROGRAM --version`'s.
cmake_minimum_required(VERSION 3.22)
foreach(required PROGRAM NAME SECTION SUMMARY OUTPUT)
  if(NOT DEFINED ${required})
    message(FATAL_ERROR "man-from-help.cmake: -D${required}= is missing")
  endif()
endforeach()

# Runs the program; its standard output, or a fatal error naming the command.
function(program_output out)
  execute_process(COMMAND ${PROGRAM} ${ARGN} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "man-from-help.cmake: '${PROGRAM} ${ARGN}' failed (${rc})")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# Text as roff: backslashes, minus signs, and lines that would start with a request.
function(roff out text)
  string(REPLACE "\\" "\\e" text "${text}")
  string(REPLACE "-" "\\-" text "${text}")
  # (CMake's ^ matches wherever a search resumes, so lines are found by their newline.)
  string(REGEX REPLACE "\n([.'])" "\n\\\\&\\1" text "\n${text}")
  string(SUBSTRING "${text}" 1 -1 text)
  string(REGEX REPLACE "\n+$" "" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# A help text split at its first blank line: the usage lines (without "usage: ") and the rest.
function(split_help usage_out rest_out text)
  string(FIND "${text}" "\n\n" cut)
  if(cut EQUAL -1)
    set(usage "${text}")
    set(rest "")
  else()
    string(SUBSTRING "${text}" 0 ${cut} usage)
    math(EXPR after "${cut} + 2")
    string(SUBSTRING "${text}" ${after} -1 rest)
  endif()
  string(REGEX REPLACE "\n(usage:|      ) " "\n" usage "\n${usage}")
  string(SUBSTRING "${usage}" 1 -1 usage)
  set(${usage_out} "${usage}" PARENT_SCOPE)
  set(${rest_out} "${rest}" PARENT_SCOPE)
endfunction()

program_output(version --version)
string(STRIP "${version}" version)
string(TOUPPER "${NAME}" title)
if(SECTION STREQUAL "8")
  set(manual "System Administration")
else()
  set(manual "User Commands")
endif()

if(SUBCOMMANDS)
  program_output(help help)
else()
  program_output(help --help)
endif()
split_help(usage description "${help}")
roff(usage "${usage}")
roff(description "${description}")
roff(summary "${SUMMARY}")
set(page ".TH ${title} ${SECTION} \"\" \"${version}\" \"${manual}\"
.SH NAME
${NAME} \\- ${summary}
.SH SYNOPSIS
.nf
${usage}
.fi
.SH DESCRIPTION
.nf
${description}
.fi
")

if(SUBCOMMANDS)
  string(APPEND page ".SH COMMANDS\n")
  string(REGEX MATCHALL "\n  [a-z][a-z0-9-]* " listed "${help}")
  foreach(entry IN LISTS listed)
    string(STRIP "${entry}" command)
    program_output(command_help ${command} --help)
    roff(command_help "${command_help}")
    string(APPEND page ".SS ${command}\n.nf\n${command_help}\n.fi\n")
  endforeach()
endif()
if(DEFINED NOTES)
  roff(notes "${NOTES}")
  string(APPEND page ".SH NOTES\n${notes}\n")
endif()
if(DEFINED SEE_ALSO)
  roff(see_also "${SEE_ALSO}")
  string(APPEND page ".SH SEE ALSO\n${see_also}\n")
endif()
file(WRITE "${OUTPUT}" "${page}")

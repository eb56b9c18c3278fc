# Writes the bash completion of robocal from the built program's help, so it cannot drift from
# the commands: the commands `robocal help` lists, and for each the options its
# `robocal COMMAND --help` names. Run at build time as a script:
#   cmake -DPROGRAM=path/to/robocal -DOUTPUT=robocal.bash -P bash-completion.cmake
cmake_minimum_required(VERSION 3.22)
foreach(required PROGRAM OUTPUT)
  if(NOT DEFINED ${required})
    message(FATAL_ERROR "bash-completion.cmake: -D${required}= is missing")
  endif()
endforeach()

function(program_output out)
  execute_process(COMMAND ${PROGRAM} ${ARGN} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "bash-completion.cmake: '${PROGRAM} ${ARGN}' failed (${rc})")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

program_output(help help)
string(REGEX MATCHALL "\n  [a-z][a-z0-9-]* " listed "${help}")
set(commands "")
set(cases "")
foreach(entry IN LISTS listed)
  string(STRIP "${entry}" command)
  program_output(command_help ${command} --help)
  string(REGEX MATCHALL "--[a-z][a-z0-9-]*" options "${command_help}")
  list(APPEND options --help)
  list(REMOVE_DUPLICATES options)
  list(SORT options)
  list(JOIN options " " options)
  list(APPEND commands ${command})
  string(APPEND cases "    ${command}) options=\"${options}\" ;;\n")
endforeach()
list(JOIN commands " " commands)

file(WRITE "${OUTPUT}" "# bash completion for robocal, made at build time from `robocal help` and
# `robocal COMMAND --help` (cli/bash-completion.cmake): the command, then its options; file
# names elsewhere.
_robocal() {
  local cur=\${COMP_WORDS[COMP_CWORD]} options
  if ((COMP_CWORD == 1)); then
    mapfile -t COMPREPLY < <(compgen -W \"${commands} help --help --version\" -- \"\$cur\")
    return 0
  fi
  case \${COMP_WORDS[1]} in
${cases}    *) return 0 ;;
  esac
  if [[ \$cur == -* ]]; then
    mapfile -t COMPREPLY < <(compgen -W \"\$options\" -- \"\$cur\")
  fi
  return 0
}
complete -o default -F _robocal robocal
")

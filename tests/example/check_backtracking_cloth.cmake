# The backtracking cloth example's steps never collide: the example writes its frames,
# and the host reference CCD (double precision, never misses) finds no contact in any
# step between them.
#   cmake -DEXAMPLE=... -DCSTREAMS=... -DWORK_DIR=... -P check_backtracking_cloth.cmake
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
execute_process(COMMAND ${EXAMPLE} --steps 40 --out ${WORK_DIR} RESULT_VARIABLE status OUTPUT_VARIABLE log)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the example failed (${status}):\n${log}")
endif()
string(REGEX MATCHALL "vertices stopped" steps "${log}")
list(LENGTH steps step_count)
string(REGEX MATCH "step size 0\\.[0-9]+" backtracked "${log}")
if(NOT step_count EQUAL 40 OR NOT backtracked)
  message(FATAL_ERROR "the example ran ${step_count} steps and backtracked ${backtracked}:\n${log}")
endif()
file(GLOB frames ${WORK_DIR}/frame_*.ply)
list(SORT frames)
execute_process(COMMAND ${CSTREAMS} reference ${frames} --out ${WORK_DIR}/contacts.csv RESULT_VARIABLE status
                ERROR_VARIABLE error)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the reference failed: ${error}")
endif()
file(STRINGS ${WORK_DIR}/contacts.csv rows)
list(LENGTH rows row_count)
if(NOT row_count EQUAL 1)
  math(EXPR contacts "${row_count} - 1")
  message(FATAL_ERROR "the reference finds ${contacts} contacts in the steps the example took")
endif()

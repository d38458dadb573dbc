# tetrapage_usage_blocks(MARKDOWN OUT_DIR PREFIX): writes each fenced ```c and ```cpp block of
# MARKDOWN to OUT_DIR/PREFIX_<k>.c or .cpp (k from 1, in order) and sets, in the caller's scope,
# PREFIX_BLOCKS (the list of k) and for each k: PREFIX_<k>_LANGUAGE (C or CXX), PREFIX_<k>_SOURCE,
# PREFIX_<k>_LINE (the block's first line in MARKDOWN) and PREFIX_<k>_OUTPUT (a file holding the
# regular expression its output must match, or empty).
#
# A block is a whole program. Two HTML comments, invisible where the Markdown is shown, qualify
# it:
#   <!-- fragment -->           on the line directly above the opening fence: the block is a
#                               part of main() in FragmentHarness.c or .cpp, whose comments say
#                               what it has in scope.
#   <!-- output: REGEX -->      on the line directly below the closing fence: what the
#                               program's standard output must match (a CMake regex).
# Each file starts with a #line directive, so that a compiler's message names MARKDOWN and the
# line. A block without main() and not marked as a fragment becomes an #error naming its line.
# Files are rewritten only when their text changes, so an edit elsewhere rebuilds nothing.

function(tetrapage_usage_blocks markdown out_dir prefix)
  file(READ "${markdown}" text)
  # A CMake list of the lines: ';', square brackets and backslashes (which would split, group
  # or escape list elements) stand in as control characters until written out.
  string(ASCII 1 semicolon)
  string(ASCII 2 open_bracket)
  string(ASCII 3 close_bracket)
  string(ASCII 4 backslash)
  string(REPLACE "\\" "${backslash}" text "${text}")
  string(REPLACE ";" "${semicolon}" text "${text}")
  string(REPLACE "[" "${open_bracket}" text "${text}")
  string(REPLACE "]" "${close_bracket}" text "${text}")
  string(REPLACE "\n" ";" lines "${text}")

  set(blocks "")
  set(count 0)
  set(number 0)
  set(inside FALSE)
  set(previous "")
  set(expect_output FALSE)
  foreach(line IN LISTS lines)
    math(EXPR number "${number} + 1")
    if(expect_output)
      set(expect_output FALSE)
      if(line MATCHES "^<!-- output: (.*) -->$")
        set(output "${CMAKE_MATCH_1}")
        string(REPLACE "${semicolon}" ";" output "${output}")
        string(REPLACE "${open_bracket}" "[" output "${output}")
        string(REPLACE "${close_bracket}" "]" output "${output}")
        string(REPLACE "${backslash}" "\\" output "${output}")
        file(WRITE "${out_dir}/${prefix}_${count}.output.new" "${output}")
        configure_file("${out_dir}/${prefix}_${count}.output.new" "${out_dir}/${prefix}_${count}.output" COPYONLY)
        file(REMOVE "${out_dir}/${prefix}_${count}.output.new")
        set(${prefix}_${count}_OUTPUT "${out_dir}/${prefix}_${count}.output" PARENT_SCOPE)
      endif()
    endif()
    if(NOT inside AND line MATCHES "^```(c|cpp)$")
      set(inside TRUE)
      math(EXPR count "${count} + 1")
      set(language C)
      set(extension c)
      if(CMAKE_MATCH_1 STREQUAL "cpp")
        set(language CXX)
        set(extension cpp)
      endif()
      math(EXPR first "${number} + 1")
      set(fragment FALSE)
      if(previous STREQUAL "<!-- fragment -->")
        set(fragment TRUE)
      endif()
      set(body "")
    elseif(inside AND line STREQUAL "```")
      set(inside FALSE)
      set(expect_output TRUE)
      string(REPLACE "${semicolon}" ";" body "${body}")
      string(REPLACE "${open_bracket}" "[" body "${body}")
      string(REPLACE "${close_bracket}" "]" body "${body}")
      string(REPLACE "${backslash}" "\\" body "${body}")
      set(where "#line ${first} \"${markdown}\"\n")
      if(fragment)
        set(harness "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/FragmentHarness.${extension}")
        file(READ "${harness}" harness_text)
        string(FIND "${harness_text}" "@USAGE_BLOCK@\n" marker)
        string(SUBSTRING "${harness_text}" 0 ${marker} before)
        math(EXPR after_marker "${marker} + 14")
        string(SUBSTRING "${harness_text}" ${after_marker} -1 after)
        # The compiler's lines point into the harness, the block and the harness again.
        string(REGEX MATCHALL "\n" breaks "${before}")
        list(LENGTH breaks after_line)
        math(EXPR after_line "${after_line} + 2")
        string(CONCAT source "#line 1 \"${harness}\"\n${before}${where}${body}"
                             "#line ${after_line} \"${harness}\"\n${after}")
      elseif(body MATCHES "int main\\(")
        set(source "${where}${body}")
      else()
        string(CONCAT source "#error \"${markdown}:${first}: a block of code must be a whole program (with main) or be "
                   "marked <!-- fragment --> on the line above it\"\n")
      endif()
      set(file "${out_dir}/${prefix}_${count}.${extension}")
      file(WRITE "${file}.new" "${source}")
      configure_file("${file}.new" "${file}" COPYONLY)
      file(REMOVE "${file}.new")
      list(APPEND blocks ${count})
      set(${prefix}_${count}_LANGUAGE ${language} PARENT_SCOPE)
      set(${prefix}_${count}_SOURCE "${file}" PARENT_SCOPE)
      set(${prefix}_${count}_LINE ${first} PARENT_SCOPE)
      set(${prefix}_${count}_OUTPUT "" PARENT_SCOPE)
      file(REMOVE "${out_dir}/${prefix}_${count}.output")
    elseif(inside)
      string(APPEND body "${line}\n")
    endif()
    set(previous "${line}")
  endforeach()
  if(inside)
    message(FATAL_ERROR "${markdown}: the block of code opened at line ${first} is never closed")
  endif()
  set(${prefix}_BLOCKS ${blocks} PARENT_SCOPE)
endfunction()

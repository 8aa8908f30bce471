# What the build scripts that compile files into `arbiter` share (cli/templates/embed.cmake,
# web/bundle.cmake), included by them in `cmake -P`.

# embedded_array(VAR SYMBOL FILE): sets VAR to the C++ definition of SYMBOL, a byte array of
# exactly FILE's bytes followed by a 0 that is not the file's, so that `sizeof SYMBOL - 1` is
# the file's size and a text file can be read as a C string.
function(embedded_array var symbol file)
  file(READ "${file}" hex HEX)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  string(REPEAT "0x..," 32 line)
  string(REGEX REPLACE "(${line})" "\\1\n" bytes "${bytes}")
  set(${var} "const unsigned char ${symbol}[] = {\n${bytes}0};\n" PARENT_SCOPE)
endfunction()

# write_generated(OUTPUT TEXT): writes TEXT to OUTPUT unless it already holds it, so that an
# unchanged file keeps its time stamp and nothing that includes it is compiled again.
function(write_generated output text)
  file(WRITE "${output}.new" "${text}")
  file(COPY_FILE "${output}.new" "${output}" ONLY_IF_DIFFERENT)
  file(REMOVE "${output}.new")
endfunction()

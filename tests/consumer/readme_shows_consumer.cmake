# Package.TheReadmeShowsTheConsumerAsBuilt: README.md ("Use it from C++") quotes the two files
# of project/ word for word, so the example a reader copies is the one this suite builds. Run
# with cmake -P and -DREADME, -DSOURCE (the project folder).
file(READ "${README}" readme)
foreach(file CMakeLists.txt trace_both.cpp)
  file(READ "${SOURCE}/${file}" text)
  string(FIND "${readme}" "${text}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "README.md does not show tests/consumer/project/${file} as it is: copy the file into "
                        "the section 'Use it from C++'")
  endif()
endforeach()

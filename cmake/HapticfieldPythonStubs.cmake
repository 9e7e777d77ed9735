# The type stubs in the build tree's package, as in an install: build/python/hapticfield/ holds the extension
# (__init__.cpython-...so), its stubs __init__.pyi and the PEP 561 marker py.typed, so mypy and editors find them
# through PYTHONPATH=build/python or MYPYPATH=build/python. Copies of python/stubs/hapticfield/, renewed when they
# change and built with the module.
#   hapticfield_python_stubs(TARGET)   TARGET: the module's target (nothing when it does not exist)
function(hapticfield_python_stubs target)
  if(NOT TARGET ${target})
    return()
  endif()
  get_target_property(dir ${target} LIBRARY_OUTPUT_DIRECTORY)
  set(stubs "${PROJECT_SOURCE_DIR}/python/stubs/hapticfield")
  add_custom_command(
    OUTPUT "${dir}/__init__.pyi" "${dir}/py.typed"
    COMMAND ${CMAKE_COMMAND} -E make_directory "${dir}"
    COMMAND ${CMAKE_COMMAND} -E copy "${stubs}/__init__.pyi" "${stubs}/py.typed" "${dir}"
    DEPENDS "${stubs}/__init__.pyi" "${stubs}/py.typed"
    COMMENT "hapticfield: type stubs beside the module in ${dir}"
    VERBATIM)
  add_custom_target(${target}_stubs ALL DEPENDS "${dir}/__init__.pyi" "${dir}/py.typed")
  add_dependencies(${target} ${target}_stubs)
endfunction()

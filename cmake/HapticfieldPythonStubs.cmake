# The type stubs beside the build tree's Python module, so that type checkers find them there as they
# do in an install (where hapticfield/ holds __init__.pyi and py.typed):
#   build/python/hapticfield.pyi               next to the module: MYPYPATH=build/python, editors (pyright)
#   build/python/hapticfield-stubs/__init__.pyi  a PEP 561 stub package: mypy through PYTHONPATH=build/python
# Copies of python/stubs/hapticfield/__init__.pyi, renewed when it changes and built with the module.
#   hapticfield_python_stubs(TARGET)   TARGET: the module's target (nothing when it does not exist)
function(hapticfield_python_stubs target)
  if(NOT TARGET ${target})
    return()
  endif()
  get_target_property(dir ${target} LIBRARY_OUTPUT_DIRECTORY)
  set(stub "${PROJECT_SOURCE_DIR}/python/stubs/hapticfield/__init__.pyi")
  add_custom_command(
    OUTPUT "${dir}/hapticfield.pyi" "${dir}/hapticfield-stubs/__init__.pyi"
    COMMAND ${CMAKE_COMMAND} -E make_directory "${dir}/hapticfield-stubs"
    COMMAND ${CMAKE_COMMAND} -E copy "${stub}" "${dir}/hapticfield.pyi"
    COMMAND ${CMAKE_COMMAND} -E copy "${stub}" "${dir}/hapticfield-stubs/__init__.pyi"
    DEPENDS "${stub}"
    COMMENT "hapticfield: type stubs beside the module in ${dir}"
    VERBATIM)
  add_custom_target(${target}_stubs ALL DEPENDS "${dir}/hapticfield.pyi" "${dir}/hapticfield-stubs/__init__.pyi")
  add_dependencies(${target} ${target}_stubs)
endfunction()

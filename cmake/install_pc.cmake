# install_pc.cmake — run by `cmake --install`: writes sqlite-affect.pc for the prefix being
# installed to (CMAKE_INSTALL_PREFIX at install time, which --prefix overrides). The install
# rules of CMakeLists.txt set AFFECT_VERSION, AFFECT_LIBDIR, AFFECT_INCLUDEDIR, AFFECT_PC_IN and
# AFFECT_PC_OUT before running it; absolute LIBDIR/INCLUDEDIR are kept as they are.
foreach(d LIBDIR INCLUDEDIR)
    if(IS_ABSOLUTE "${AFFECT_${d}}")
        set(AFFECT_PC_${d} "${AFFECT_${d}}")
    else()
        set(AFFECT_PC_${d} "\${prefix}/${AFFECT_${d}}")
    endif()
endforeach()
configure_file("${AFFECT_PC_IN}" "${AFFECT_PC_OUT}" @ONLY)

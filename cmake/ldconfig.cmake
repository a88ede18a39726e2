# ldconfig.cmake — run by `cmake --install` after the module is in place: makes `.load affect`
# find it from any directory (see "install" in CMakeLists.txt for how SQLite and dlopen resolve
# the bare name).
#
# It acts only when installing as root, without DESTDIR (a package's postinst runs ldconfig
# itself), into a directory that ldconfig scans (listed by `ldconfig -v -N -X`: /etc/ld.so.conf
# and the default directories). Then it runs ldconfig, which caches "affect.so" under the link
# libaffect.so, and checks that the cache now names our file. Otherwise it says what to do.
# AFFECT_LIBDIR is set by the install rules of CMakeLists.txt.
if(IS_ABSOLUTE "${AFFECT_LIBDIR}")
    set(libdir "${AFFECT_LIBDIR}")
else()
    set(libdir "${CMAKE_INSTALL_PREFIX}/${AFFECT_LIBDIR}")
endif()
get_filename_component(libdir "${libdir}" ABSOLUTE)
set(hint "set LD_LIBRARY_PATH=${libdir} for `.load affect`, or load it by path: \
.load ${libdir}/affect")
if(NOT "$ENV{DESTDIR}" STREQUAL "")
    return()
endif()
execute_process(COMMAND id -u OUTPUT_VARIABLE uid OUTPUT_STRIP_TRAILING_WHITESPACE)
find_program(AFFECT_LDCONFIG ldconfig PATHS /sbin /usr/sbin NO_CACHE)
if(NOT uid STREQUAL "0" OR NOT AFFECT_LDCONFIG)
    message(STATUS
        "sqlite-affect: not root (or no ldconfig), the loader's cache is unchanged: ${hint}")
    return()
endif()
execute_process(COMMAND ${AFFECT_LDCONFIG} -v -N -X OUTPUT_VARIABLE scanned ERROR_QUIET)
string(REGEX MATCHALL "(^|\n)/[^:\n]*:" dirs "${scanned}")
set(searched FALSE)
foreach(d ${dirs})
    string(REGEX REPLACE "^\n?(.*):$" "\\1" d "${d}")
    if(d STREQUAL libdir)
        set(searched TRUE)
    endif()
endforeach()
if(NOT searched)
    message(STATUS "sqlite-affect: ${libdir} is not searched by the dynamic loader: ${hint}")
    return()
endif()
execute_process(COMMAND ${AFFECT_LDCONFIG} RESULT_VARIABLE rc)
execute_process(COMMAND ${AFFECT_LDCONFIG} -p OUTPUT_VARIABLE cache ERROR_QUIET)
if(rc EQUAL 0 AND cache MATCHES "\taffect\\.so \\([^)]*\\) => ${libdir}/affect\\.so\n")
    message(STATUS "sqlite-affect: ran ldconfig: `.load affect` loads ${libdir}/affect.so")
else()
    message(WARNING "sqlite-affect: ldconfig did not cache ${libdir}/affect.so: ${hint}")
endif()

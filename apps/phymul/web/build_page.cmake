# cmake -P: npm ci when package-lock.json changed, then esbuild when a source changed. A
# missing tool or registry leaves the page out with a warning; the build goes on.
function(give_up why)
  message(WARNING "phymul serve's page not built: ${why}. The server is built; the browser "
                  "tests will be skipped.")
  file(REMOVE ${OUT}/app.js ${OUT}/index.html)
endfunction()

if(NOT NPM OR NOT ESBUILD)
  give_up("npm or esbuild not found (Debian: apt-get install npm esbuild)")
  return()
endif()
set(stamp ${NPM_DIR}/node_modules/.package-lock.json)
if(NOT EXISTS ${stamp} OR ${SOURCE}/package-lock.json IS_NEWER_THAN ${stamp})
  file(MAKE_DIRECTORY ${NPM_DIR})
  file(COPY ${SOURCE}/package.json ${SOURCE}/package-lock.json DESTINATION ${NPM_DIR})
  execute_process(COMMAND ${NPM} ci --no-audit --no-fund --loglevel=error
                  WORKING_DIRECTORY ${NPM_DIR} RESULT_VARIABLE failed)
  if(failed OR NOT EXISTS ${stamp})
    give_up("npm ci failed in ${NPM_DIR}")
    return()
  endif()
  file(TOUCH ${stamp})
endif()

file(GLOB sources ${SOURCE}/*.js ${SOURCE}/*.html ${SOURCE}/*.css)
set(stale FALSE)
foreach(s ${sources} ${stamp})
  if(NOT EXISTS ${OUT}/app.js OR s IS_NEWER_THAN ${OUT}/app.js)
    set(stale TRUE)
  endif()
endforeach()
if(NOT stale)
  return()
endif()
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${NPM_DIR}/node_modules
                        ${ESBUILD} ${SOURCE}/main.js --bundle --minify --target=es2020
                        --log-level=warning --outfile=${OUT}/app.js
                RESULT_VARIABLE failed)
if(failed)
  give_up("esbuild failed")
  return()
endif()
file(COPY ${SOURCE}/index.html DESTINATION ${OUT})

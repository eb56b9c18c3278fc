// The console's page (daemon/web/console.html), compiled into robocald by CMake
// (console_page.cpp.in): the cell PC needs nothing from elsewhere.
#pragma once

namespace robocal::daemon {
extern const char* const kConsoleHtml;
}

// MapWindow without OpenCV viz: there is no 3D window (the viewer shows the top view instead).
#include "tools/viewer/map_window.hpp"

namespace heslam::viewer {

std::unique_ptr<MapWindow> MapWindow::create() { return nullptr; }

}  // namespace heslam::viewer

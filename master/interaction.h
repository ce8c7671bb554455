// Interactive camera control: how the display's drag/wheel input moves the camera.
#pragma once
#include <string>

#include "common/camera.h"
#include "common/scene.h"
#include "common/wire/protocol.h"

namespace tessera::master {

// Orbits the eye about the target (dx about `up`, dy about the camera's right axis,
// refusing to tilt onto the pole) and scales its distance by zoom (clamped to 0.2..5; the
// distance stays within the scene file's camera limits).
// Throws std::invalid_argument for non-finite values or zoom <= 0.
Camera applyInput(const Camera& cam, const proto::Input& in);

// What the master says once the user has set a colour window (the drag released): the values
// the colour map now spans and the scene's `window` that keeps it (`scene`'s range fixed).
std::string windowNote(const Scene& scene, const ColorWindow& w);

// What the master says as an interactive run starts: how to steer and stop it.
inline constexpr const char* kSteeringNotice =
    "interactive run: a frame is rendered when the display's window or web view sends input (drag: orbit, wheel: zoom, right-drag: colour window, "
    "Space: play a series, h: help); without either only the first frame is rendered (a series plays on). Ctrl-C or "
    "closing the window stops it";

}  // namespace tessera::master

// Test helper: a user's mouse and keyboard on an X server, through the XTEST extension (Xvfb
// has it): the events reach the window exactly as a person's would. Also finds a top-level
// window by its title and resizes it (there is no window manager on Xvfb). Include it last.
#pragma once
#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/extensions/XTest.h>
#include <X11/keysym.h>

#include <chrono>
#include <optional>
#include <string>
#include <thread>

namespace tessera::display::testing {

class XUser {
 public:
  explicit XUser(const std::string& display) : dpy_(XOpenDisplay(display.c_str())) {
    // A window that goes between XQueryTree and a query of it (the display's window being
    // made or closed) raises BadWindow, and Xlib's default handler ends the process: the
    // query just fails instead.
    XSetErrorHandler([](Display*, XErrorEvent*) { return 0; });
  }
  ~XUser() {
    if (dpy_) XCloseDisplay(dpy_);
  }
  XUser(const XUser&) = delete;
  XUser& operator=(const XUser&) = delete;
  bool ok() const {
    int ev, err, major, minor;
    return dpy_ && XTestQueryExtension(dpy_, &ev, &err, &major, &minor);
  }

  struct Geometry {
    Window window = 0;
    int x = 0, y = 0, width = 0, height = 0;  // on the root window
  };
  // The mapped top-level window whose title is `title`.
  std::optional<Geometry> find(const std::string& title) {
    Window root = DefaultRootWindow(dpy_), parent, *children = nullptr;
    unsigned n = 0;
    if (!XQueryTree(dpy_, root, &root, &parent, &children, &n)) return std::nullopt;
    std::optional<Geometry> found;
    for (unsigned i = 0; i < n && !found; ++i) {
      char* name = nullptr;
      XWindowAttributes a;
      if (XFetchName(dpy_, children[i], &name) && name && title == name && XGetWindowAttributes(dpy_, children[i], &a) &&
          a.map_state == IsViewable)
        found = Geometry{children[i], a.x, a.y, a.width, a.height};
      if (name) XFree(name);
    }
    if (children) XFree(children);
    return found;
  }
  void moveTo(int x, int y) { XTestFakeMotionEvent(dpy_, -1, x, y, CurrentTime), flush(); }
  void button(int b, bool down) { XTestFakeButtonEvent(dpy_, (unsigned)b, down, CurrentTime), flush(); }
  void key(KeySym sym) {
    const KeyCode code = XKeysymToKeycode(dpy_, sym);
    XTestFakeKeyEvent(dpy_, code, True, CurrentTime);
    XTestFakeKeyEvent(dpy_, code, False, CurrentTime);
    flush();
  }
  void resize(Window w, int width, int height) { XResizeWindow(dpy_, w, (unsigned)width, (unsigned)height), flush(); }
  // The pointer into the window, a moment for the window to see it enter, then the left
  // button down (a press that races the pointer's arrival was seen to start no drag).
  void press(int x, int y) {
    moveTo(x, y);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    button(1, true);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  // A left-button drag from (x, y) by (dx, dy) per step, `steps` steps `pause` apart.
  void drag(int x, int y, int dx, int dy, int steps, std::chrono::milliseconds pause) {
    press(x, y);
    for (int i = 1; i <= steps; ++i) {
      moveTo(x + i * dx, y + i * dy);
      std::this_thread::sleep_for(pause);
    }
    button(1, false);
  }

 private:
  void flush() { XFlush(dpy_); }
  Display* dpy_;
};

}  // namespace tessera::display::testing

// Xlib's macros collide with ordinary names (AaMethod::None, Status...): include this header
// after the project's, and let nothing below see them.
#undef None
#undef Bool
#undef Status
#undef True
#undef False
#undef Always
#undef Success

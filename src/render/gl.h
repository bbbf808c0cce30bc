// OpenGL entry points: called directly through glvnd's libOpenGL, which dispatches to whatever
// context is current (GLX from GLFW or EGL), so no loader library is needed.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/gl.h>
#include <GL/glext.h>

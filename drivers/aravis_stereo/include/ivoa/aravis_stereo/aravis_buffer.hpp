#pragma once
// Copies an Aravis buffer into a CameraFrame, refusing incomplete ones.
#include <arv.h>

#include "ivoa/aravis_stereo/aravis_camera.hpp"
#include "ivoa/aravis_stereo/camera_source.hpp"

namespace ivoa::aravis_stereo {

// A complete frame with tightly packed rows, or (complete = false) the
// reason the buffer cannot be used: lost packets, unmapped pixel format,
// wrong size. Never returns partial pixels. pairing_time_us is the host
// receive time until the driver chooses otherwise.
FrameResult buffer_to_frame(ArvBuffer* buffer, Side side);

// False for a buffer the stream handed back without filling it (status
// "cleared": Aravis 0.8 does so as a stream starts): no frame is behind
// it, so it is neither a frame nor a lost one.
bool buffer_was_filled(ArvBuffer* buffer);

// "missing packets", "timeout", ... for log lines.
const char* buffer_status_name(ArvBufferStatus status);

}  // namespace ivoa::aravis_stereo

// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse preview`: a local web page that plays a scene as it renders and follows its file
// (README "Preview"). Internal to app/.

#include <string>
#include <vector>

namespace impulse::app {

struct PreviewOptions {
    std::string scene;                ///< scene file or built-in name
    std::string host = "127.0.0.1";   ///< address to listen on (local only by default)
    int port = 8080;                  ///< 0: any free port (printed)
    std::string size;                 ///< "WxH" preview size; default: within 640x360, same view
    std::vector<std::string> expose;  ///< numeric keys given sliders: key or key=lo:hi
    std::vector<std::string> sets;    ///< --set overrides, as in render
};

/// Serves the preview until SIGINT, SIGTERM or SIGHUP; returns 0 then. Throws IoError when the
/// port cannot be listened on (naming it and the reason) and ValueError for a bad option.
int run_preview(const PreviewOptions& options);

}  // namespace impulse::app

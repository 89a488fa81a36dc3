// SPDX-License-Identifier: Apache-2.0
// `impulse preview SCENE`: a local web server (cpp-httplib) with one page that plays the scene as
// it renders (app/preview_page.html), follows the scene's files and exposes keys as sliders.

#include "app/preview.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <iostream>
#include <regex>

#include "app/detail/preview.h"
#include "numeric/errors.h"

namespace impulse::app {

extern const char* const kPreviewPage;  // app/preview_page.html, embedded by CMake

namespace {

using preview::Previewer;

/// The preview size: --size, else the scene's own size fitted within 640x360 (the same view:
/// load_scene's size keeps the framing).
scenes::OutputSize preview_size(const std::string& path, const std::vector<std::string>& sets,
                                const std::string& size) {
    if (!size.empty()) {
        static const std::regex re(R"((\d{1,4})x(\d{1,4}))");
        std::smatch m;
        if (!std::regex_match(size, m, re) || std::stoi(m[1]) < 16 || std::stoi(m[2]) < 16)
            throw ValueError("--size " + size.substr(0, 40) +
                             ": expected WxH in pixels, each in [16, 9999], e.g. 640x360");
        return {std::stoi(m[1]), std::stoi(m[2])};
    }
    int w = 640, h = 360;
    try {
        const scenes::Scene s = scenes::load_scene(path, sets);
        const double scale = std::min({1.0, 640.0 / s.output.width, 360.0 / s.output.height});
        w = std::max(16, int(std::lround(s.output.width * scale)));
        h = std::max(16, int(std::lround(s.output.height * scale)));
    } catch (const Error&) {
        // A scene that does not load yet: the page shows why, at 640x360 until it does.
    }
    return {w, h};
}

/// Why nothing can listen on host:port (the system's reason), for the one-line error.
std::string bind_problem(const std::string& host, int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return std::strerror(errno);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    std::string why = "cannot listen";
    if (::inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1)
        why = "not an IPv4 address";
    else if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0)
        why = errno == EADDRINUSE ? "port in use (another program listens on it; --port N or "
                                    "--port 0 for a free one)"
                                  : std::strerror(errno);
    ::close(fd);
    return why;
}

bool parse_integer(const std::string& s, long long& v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
}

void refuse(httplib::Response& res, int status, const std::string& line) {
    res.status = status;
    res.set_content(line + "\n", "text/plain; charset=utf-8");
}

/// The routes. Nothing is served from disk: any other path is refused.
void add_routes(httplib::Server& svr, Previewer& p) {
    svr.Get("/", [](const httplib::Request&, httplib::Response& res) {
        res.set_content(kPreviewPage, "text/html; charset=utf-8");
    });
    svr.Get("/state", [&p](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_content(p.state_json(), "application/json");
    });
    svr.Get("/frame", [&p](const httplib::Request& req, httplib::Response& res) {
        long long g = 0, f = 0;
        if (!parse_integer(req.get_param_value("g"), g) ||
            !parse_integer(req.get_param_value("i"), f))
            return refuse(res, 400, "/frame: expected ?g=GENERATION&i=FRAME");
        const auto im = p.frame(uint64_t(g), f);
        if (!im) return refuse(res, 404, "frame " + std::to_string(f) + " is not rendered yet");
        res.set_header("Cache-Control", "no-store");
        res.set_header("X-Time", std::to_string(im->time_s));
        res.set_header("X-Mean", std::to_string(im->mean));
        res.set_header("X-Variance", std::to_string(im->variance));
        res.set_header("X-Theory-Mean", std::to_string(im->theory_mean));
        res.set_header("X-Theory-Variance", std::to_string(im->theory_variance));
        res.set_header("X-Render-Ms", std::to_string(im->render_ms));
        res.set_content(im->png, "image/png");
    });
    svr.Post("/set", [&p](const httplib::Request& req, httplib::Response& res) {
        const std::string why = p.set(req.get_param_value("key"), req.get_param_value("value"));
        if (!why.empty()) return refuse(res, 400, why);
        res.set_content("ok\n", "text/plain");
    });
    // Paths that climb out of the served set are refused before routing (nothing is served
    // from disk in any case).
    svr.set_pre_routing_handler([](const httplib::Request& req, httplib::Response& res) {
        if (req.path.find("..") == std::string::npos && req.path.find('\\') == std::string::npos)
            return httplib::Server::HandlerResponse::Unhandled;
        refuse(res, 403, req.path.substr(0, 80) + ": outside what the preview serves");
        return httplib::Server::HandlerResponse::Handled;
    });
    svr.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
        if (res.body.empty())
            res.set_content(
                req.path.substr(0, 80) + ": " +
                    (res.status == 404 ? "not found" : "HTTP " + std::to_string(res.status)) +
                    " (the preview serves /, /state, /frame and /set)\n",
                "text/plain; charset=utf-8");
    });
}

/// Bounds on what a request may cost: small bodies, short timeouts, few keep-alive requests.
/// The socket takes SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, with which a second
/// preview on the same port would start and share the requests instead of being refused.
void bound_requests(httplib::Server& svr) {
    svr.set_socket_options([](socket_t sock) {
        const int yes = 1;
        ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    svr.set_payload_max_length(16 * 1024);
    svr.set_read_timeout(5, 0);
    svr.set_write_timeout(5, 0);
    svr.set_keep_alive_max_count(1000);
    svr.set_keep_alive_timeout(5);
}

}  // namespace

int run_preview(const PreviewOptions& opt) {
    if (opt.port < 0 || opt.port > 65535)
        throw ValueError("--port " + std::to_string(opt.port) + ": expected 0 .. 65535");
    preview::PreviewConfig config;
    config.path = scenes::resolve_scene(opt.scene);
    config.sets = opt.sets;

    // The stop signals are taken by one thread (sigwait) that stops the server: every thread
    // started from here (the server's, the worker's, TBB's) inherits the blocked mask.
    sigset_t stops;
    sigemptyset(&stops);
    for (const int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&stops, s);
    pthread_sigmask(SIG_BLOCK, &stops, nullptr);

    httplib::Server svr;
    bound_requests(svr);
    const int port = opt.port == 0 ? svr.bind_to_any_port(opt.host)
                                   : (svr.bind_to_port(opt.host, opt.port) ? opt.port : -1);
    if (port < 0)
        throw IoError(opt.host + ":" + std::to_string(opt.port) + ": " +
                      bind_problem(opt.host, opt.port));
    // After the port: a port in use is said at once, not after the scene has loaded.
    config.size = preview_size(config.path, opt.sets, opt.size);
    config.exposed = preview::exposed_keys(config.path, opt.expose);
    Previewer previewer(config);
    add_routes(svr, previewer);
    std::atomic<bool> signalled{false};
    std::thread stopper([&] {
        int signo = 0;
        sigwait(&stops, &signo);
        signalled = true;
        svr.stop();
    });
    std::cout << "preview: http://" << opt.host << ":" << port << "/ (" << config.path << ", "
              << config.size.width << "x" << config.size.height << "; Ctrl-C stops)" << std::endl;
    const bool ok = svr.listen_after_bind();
    if (!signalled) pthread_kill(stopper.native_handle(), SIGTERM);  // stopped on its own
    stopper.join();
    std::cout << "preview stopped" << std::endl;
    return ok ? 0 : 1;
}

}  // namespace impulse::app

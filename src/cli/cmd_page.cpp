// `latentbench page DIR...`: (re)write each suite folder's index.html from the files in it
// (pipeline/html_page.hpp): a run's output folder or a published results/ folder. With
// --listing FILE, also a page linking every one of them.
#include <cstdio>

#include "cli/commands.hpp"
#include "pipeline/html_page.hpp"

namespace lb::cli {

void register_page(CLI::App& app)
{
    struct Args {
        std::vector<std::string> dirs;
        std::string listing;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "page", "Write a suite folder's index.html (tables, figures, videos, provenance) from the files in it");
    cmd->add_option("dirs", a->dirs, "Suite folders: a run's output folder or a published results/ folder")->required();
    cmd->add_option("--listing", a->listing, "Also write this page, linking every suite page written");
    cmd->callback([a] {
        for (const std::string& dir : a->dirs) std::printf("wrote %s\n", write_suite_page(dir).c_str());
        if (!a->listing.empty()) std::printf("wrote %s\n", write_suite_listing(a->dirs, a->listing).c_str());
    });
}

} // namespace lb::cli

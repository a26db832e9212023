// `curvefem schema` prints the case-file schema (pipeline/case_schema.hpp): `--markdown` the key
// table of cases/README.md, `--json` every key as a JSON array; `--update README` rewrites the
// table between the README's `<!-- schema:begin -->` / `<!-- schema:end -->` markers.
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "pipeline/case_schema.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {

void register_schema(CLI::App& app) {
  struct Args {
    bool markdown = false, json = false;
    std::string update;
    GlobalOptions global;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "schema", "print the case-file keys (type, default, allowed values, meaning)");
  sub->add_flag("--markdown", args->markdown, "the key table of cases/README.md (default)");
  sub->add_flag("--json", args->json, "every key as a JSON array of objects");
  sub->add_option("--update", args->update,
                  "rewrite the table between the schema markers of this Markdown file");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    apply_global_options(args->global);
    if (args->markdown + args->json + !args->update.empty() > 1)
      throw InputError("schema: give one of --markdown, --json, --update FILE");
    if (args->json) {
      std::printf("%s\n", pipeline::case_schema_json().dump(2).c_str());
    } else if (!args->update.empty()) {
      std::ifstream in(args->update);
      if (!in) throw IoError("cannot open", {.file = args->update});
      std::stringstream text;
      text << in.rdbuf();
      std::string updated;
      try {
        updated = pipeline::replace_schema_block(text.str(), pipeline::case_schema_markdown());
      } catch (const Error& e) {
        throw InputError(e.what(), {.file = args->update});
      }
      if (updated != text.str()) write_text_file_atomic(args->update, updated);
    } else {
      std::fputs(pipeline::case_schema_markdown().c_str(), stdout);
    }
    return 0;
  });
}

}  // namespace curvefem::cli

// `curvefem schema` prints the case-file schema (pipeline/case_schema.hpp): `--markdown` the key
// table of cases/README.md, `--json` every key as a JSON array; `--study` the same for study
// files. `--update README` rewrites the case table between the README's `<!-- schema:begin -->` /
// `<!-- schema:end -->` markers and, when it has them, the study table between
// `<!-- study-schema:begin -->` / `<!-- study-schema:end -->`.
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
    bool markdown = false, json = false, study = false;
    std::string update;
    GlobalOptions global;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "schema", "print the case-file keys (type, default, allowed values, meaning)");
  sub->add_flag("--markdown", args->markdown, "the key table of cases/README.md (default)");
  sub->add_flag("--json", args->json, "every key as a JSON array of objects");
  sub->add_flag("--study", args->study, "the keys of study files (curvefem study) instead");
  sub->add_option("--update", args->update,
                  "rewrite the table between the schema markers of this Markdown file");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    apply_global_options(args->global);
    if (args->markdown + args->json + !args->update.empty() > 1)
      throw InputError("schema: give one of --markdown, --json, --update FILE");
    if (args->study && !args->update.empty())
      throw InputError("schema: --update rewrites both tables; it takes no --study");
    if (args->json) {
      std::printf("%s\n",
                  (args->study ? pipeline::study_schema_json() : pipeline::case_schema_json())
                      .dump(2)
                      .c_str());
    } else if (!args->update.empty()) {
      std::ifstream in(args->update);
      if (!in) throw IoError("cannot open", {.file = args->update});
      std::stringstream text;
      text << in.rdbuf();
      std::string updated;
      try {
        updated = pipeline::replace_schema_block(text.str(), pipeline::case_schema_markdown());
        if (updated.find(pipeline::k_study_schema_begin) != std::string::npos)
          updated = pipeline::replace_schema_block(updated, pipeline::study_schema_markdown(),
                                                   pipeline::k_study_schema_begin,
                                                   pipeline::k_study_schema_end);
      } catch (const Error& e) {
        throw InputError(e.what(), {.file = args->update});
      }
      if (updated != text.str()) write_text_file_atomic(args->update, updated);
    } else {
      std::fputs(
          (args->study ? pipeline::study_schema_markdown() : pipeline::case_schema_markdown())
              .c_str(),
          stdout);
    }
    return 0;
  });
}

}  // namespace curvefem::cli

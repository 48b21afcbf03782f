//! One stabilizer numbering everywhere (issue 23): stab1 is the stabilizer nearest the bit
//! in the static side-force plot's labels, in the ensemble's keys (`k_e.stab1`,
//! `stab1.from_bit`), in the report's columns and in the dynamic run's file names — all read
//! from `Model::stabilizer_sites`.

use std::path::Path;

use holewall::ensemble::{apply, Variant};
use holewall::keys::Key;

fn case() -> holewall::case::Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper_three_stabilizers.toml");
    holewall::case::load_case(&path).unwrap()
}

#[test]
fn plot_labels_and_ensemble_keys_name_the_same_stabilizer() {
    let case = case();
    let model = &case.model;
    let sites = model.stabilizer_sites();
    assert_eq!(sites.len(), 3, "the paper's three-stabilizer assembly");
    // Nearest the bit first: MD falls along the list.
    let md: Vec<f64> = sites
        .iter()
        .map(|&s| model.nodes[model.sites[s].node].md)
        .collect();
    assert!(md[0] > md[1] && md[1] > md[2], "{md:?}");

    // The side-force plot's labels.
    let sol = holewall::solve::statics::solve_static(model, &Default::default()).unwrap();
    let (rows, ..) = holewall::profile::fe_rows(model, &sol);
    let labels = holewall::cli::static_cmd::stabilizer_labels(model, &rows);
    assert_eq!(labels.len(), 3);
    for (k, (label, label_md, _)) in labels.iter().enumerate() {
        assert!(label.starts_with(&format!("stab{}:", k + 1)), "{label}");
        assert_eq!(*label_md, md[k], "{label}");
    }

    // The ensemble key k_e.stab1 changes the wall stiffness of the site labelled stab1 alone.
    for k in 1..=3 {
        let key = Key::parse(&format!("k_e.stab{k}")).unwrap();
        let variant = Variant {
            name: "v".into(),
            overrides: vec![(key, holewall::ensemble::Value::Number(1.2345e7))],
        };
        let varied = apply(&case, &variant).unwrap();
        let changed: Vec<usize> = (0..model.sites.len())
            .filter(|&s| varied.sites[s].params.wall_stiffness == 1.2345e7)
            .collect();
        assert_eq!(changed, vec![sites[k - 1]], "k_e.stab{k}");
        let changed_md = model.nodes[model.sites[changed[0]].node].md;
        assert_eq!(
            changed_md,
            labels[k - 1].1,
            "k_e.stab{k} against the plot's stab{k}"
        );
    }
    // The number of a site, and back.
    let numbers = model.stabilizer_numbers();
    for (k, &s) in sites.iter().enumerate() {
        assert_eq!(numbers[s], k + 1);
    }
    assert_eq!(
        numbers.iter().filter(|&&n| n == 0).count(),
        model.sites.len() - 3
    );
    assert_eq!(holewall::model::stabilizer_name(2), "stab2");
}
